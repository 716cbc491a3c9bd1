"""Projector channels rendered offscreen through EGL (Mesa llvmpipe here): what each channel
shows, where its horizon sits, blending between neighbours, and floe poses in the pixels."""
import dataclasses
import math
from datetime import datetime

import numpy as np
import pytest
from conftest import run_cli

from bridge_node.node.config import ConfigError, load_config
from bridge_node.render.camera import channel_camera
from bridge_node.render.channels import ChannelSet, blend_ramp
from bridge_node.render.meshes import CELL_VERTEX, cell_vertices, template_meshes
from bridge_node.render.floe_buffers import FloeBuffer, FloeCopies, horizon_split
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.render.warp import WarpError, write_pfm
from bridge_node.stream.world_view import WorldView
from sim_core.ice.floes import FloeStatus
from sim_core.world import snapshot

W, H = 192, 108


def channel(name="c", **kw) -> ChannelSettings:
    return ChannelSettings(name=name, width=W, height=H, **kw)


def view_of(model, data, **ship) -> WorldView:
    """A fresh view of the world's published state, optionally with the ship moved."""
    view = WorldView()
    view.apply(snapshot(model, data))
    view.ship = dataclasses.replace(view.ship, **ship)
    return view


def render(ctx, model, data, channels, visibility=8000.0, blended=True, view=None, **look):
    """Images of the channels; unblended: the same channels with their blend bands off;
    look: more render settings."""
    if not blended:
        channels = [c.model_copy(update={"blend_left_deg": 0.0, "blend_right_deg": 0.0}) for c in channels]
    settings = RenderSettings(channels=channels, **look)
    view = view or view_of(model, data)
    at_start(view, visibility, settings.start_utc)
    cs = ChannelSet(SceneRenderer(ctx, model, settings), channels)
    cs.render(view)
    return [t.image() for t in cs.targets]


def at_start(view: WorldView, visibility: float, start_utc) -> None:
    """The view's environment and exercise clock as a world started with this visibility
    (m) and date and time would publish them (the channels draw what the world publishes)."""
    view.environment = dataclasses.replace(view.environment, visibility=visibility)
    view.ship = dataclasses.replace(view.ship, utc=start_utc.timestamp() + view.time)


def is_sky(px):
    return (px[..., 2].astype(int) - px[..., 0] > 25) & (px.mean(axis=-1) > 120)


def is_water(px):
    return px.mean(axis=-1) < 90


def is_ice(px):
    return (px.mean(axis=-1) > 170) & (np.abs(px[..., 2].astype(int) - px[..., 0]) < 30)


def test_open_water_view_shows_sky_and_water(ctx, exercise):
    model, data = exercise
    south = view_of(model, data, north=-3000.0)  # 3 km south of the field, looking south: open water
    img, = render(ctx, model, data, [channel(yaw_deg=180.0, eye=[-80.0, 0.0, 20.0])], view=south)
    assert is_sky(img[: H // 3]).mean() > 0.95
    assert is_water(img[-H // 4:]).mean() > 0.95


def test_ice_field_ahead_and_the_other_side(ctx, exercise):
    model, data = exercise
    ahead, behind = render(ctx, model, data, [channel("ahead", pitch_deg=-20.0, eye=[80.0, 0.0, 20.0]),
                                              channel("behind", yaw_deg=180.0, pitch_deg=-20.0, eye=[80.0, 0.0, 20.0])])
    rows = slice(H // 2, None)  # below the horizon, near the ship
    assert is_ice(ahead[rows]).mean() > 0.6  # level ice ahead of the bow
    # the ship's own channel astern: broken floes and open water, darker than level ice
    assert behind[rows][:, W // 3: 2 * W // 3].mean() < ahead[rows][:, W // 3: 2 * W // 3].mean() - 40
    assert not np.array_equal(ahead, behind)


@pytest.mark.parametrize("pitch", [-10.0, 0.0, 12.0])
def test_horizon_sits_where_pitch_and_fov_put_it(ctx, exercise, pitch):
    model, data = exercise
    c = channel(yaw_deg=180.0, pitch_deg=pitch, eye=[-80.0, 0.0, 20.0])
    midnight_sun = datetime.fromisoformat("2026-06-21T22:40:00+00:00")  # low in the north, behind the channel
    img, = render(ctx, model, data, [c], visibility=100_000.0, start_utc=midnight_sun)
    column = img[:, W // 2].astype(float).mean(axis=1)
    # the sky brightens down to the horizon; the sea below it is darker, though it mirrors the sky
    first_dark = int(np.argmax(column < np.maximum.accumulate(column) - 12.0))
    # horizon (elevation ~0: the sea edge at 20 km lies 0.06 deg below it) in NDC: -tan(pitch)/tan(vfov/2)
    y_ndc = -math.tan(math.radians(pitch)) / math.tan(c.vfov() / 2)
    expected = (1 - y_ndc) / 2 * H
    assert abs(first_dark - expected) <= 1.5


def triangle_area(tris: np.ndarray) -> float:
    """Summed area of triangles (3 m, 2+) in their first two coordinates."""
    u, v = tris[1::3, :2] - tris[0::3, :2], tris[2::3, :2] - tris[0::3, :2]
    return float(np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]).sum() / 2)


@pytest.mark.parametrize("pitch", [0.0, -10.0, 60.0, -60.0])
def test_environment_and_sky_passes_split_the_screen_at_the_horizon(pitch):
    c = channel(pitch_deg=pitch)
    cam = channel_camera(c, (0.0, 0.0, 30.0), 0.0, 0.0, 0.3, 20_000.0)
    tx, ty = math.tan(math.radians(c.hfov_deg) / 2), math.tan(c.vfov() / 2)
    ground, sky = horizon_split(cam, tx, ty, c.width, c.height)
    assert triangle_area(ground) + triangle_area(sky) == pytest.approx(4.0)  # the whole screen, once
    horizon = np.clip(-math.tan(math.radians(pitch)) / ty, -1.0, 1.0)  # NDC y
    assert triangle_area(ground) / 4.0 == pytest.approx((1.0 + horizon) / 2.0, abs=0.01)
    band = 2.0 * ty / c.height * math.cos(math.radians(pitch))  # one pixel row's change of the ray's z
    assert np.all(sky[:, 4] >= band - 1e-9)  # the sky pass starts above the horizon's blended pixels
    assert np.all(ground[:, 4] <= 1.5 * band)


def test_template_meshes_keep_each_vertex_once_and_every_triangle(ctx, exercise):
    model, _ = exercise
    corners, start, side_start = cell_vertices(model)
    for k, mesh in enumerate(template_meshes(model)):
        g0, g1 = model.ice.template_start[k], model.ice.template_start[k + 1]
        mine = corners[start[g0]:start[g1]]
        assert len(mesh.vertices) < 0.8 * len(mine) and len(mesh.index) == len(mine)
        np.testing.assert_array_equal(mesh.vertices["pos"][mesh.index], mine[:, :3])
        np.testing.assert_array_equal(mesh.vertices["normal"][mesh.index], mine[:, 3:])
        cells = np.arange(g1 - g0)
        tops, sides = mesh.corners(cells, sides=False), mesh.corners(cells, sides=True)
        assert len(tops) + len(sides) == len(mine)
        assert np.all(mesh.vertices["normal"][tops][:, 2] > 0.5) and np.all(mesh.vertices["normal"][sides][:, 2] <= 0.5)
        owner = np.repeat(cells, np.diff(start[g0:g1 + 1]))
        np.testing.assert_array_equal(mesh.vertices["cell"][mesh.index], owner)


@pytest.mark.parametrize("copies", [False, True], ids=["frozen-indices", "live-copies"])
def test_a_tiles_floe_buffer_keeps_every_triangle_over_its_growth(ctx, exercise, copies):
    model, _ = exercise
    renderer = SceneRenderer(ctx, model, RenderSettings(channels=[channel()]))
    mesh = renderer.meshes[0]
    buf = FloeCopies(ctx, renderer.floes.program, mesh) if copies else \
        FloeBuffer(ctx, renderer.floes.program, renderer.mesh_vbos[0], mesh.index.dtype)
    cells = np.array_split(np.arange(len(mesh.start) - 1), 12)
    parts = [mesh.corners(c, sides=s) for _ in range(3) for c in cells for s in (False, True)]
    for part in parts:  # appended in parts, as cells break, over the storages' growth
        buf.append(part)
    stored = np.frombuffer(buf.ibo.read(size=buf.indices * mesh.index.itemsize), dtype=mesh.index.dtype)
    held = buf.vertex_count if copies else len(mesh.vertices)
    vertices = np.frombuffer(buf.vbo.read(size=held * CELL_VERTEX.itemsize), dtype=CELL_VERTEX)
    np.testing.assert_array_equal(vertices[stored], mesh.vertices[np.concatenate(parts)])
    assert buf.ibo.size > 1 << 16  # it grew past its first storage
    if copies:  # each vertex once per part
        assert buf.vertex_count == sum(len(np.unique(p)) for p in parts)


def neighbours():
    return [channel("left", yaw_deg=-27.5, blend_right_deg=5.0, pitch_deg=-15.0, eye=[-70.0, 0.0, 20.0]),
            channel("right", yaw_deg=27.5, blend_left_deg=5.0, pitch_deg=-15.0, eye=[-70.0, 0.0, 20.0])]


def column_at(c: ChannelSettings, azimuth_deg: float) -> int:
    """Pixel column showing the azimuth (deg from the channel's centre)."""
    t = math.tan(math.radians(azimuth_deg)) / math.tan(math.radians(c.hfov_deg) / 2)
    return int(round((t + 1) / 2 * c.width - 0.5))


def test_neighbouring_channels_agree_in_their_overlap(ctx, exercise):
    model, data = exercise
    left, right = neighbours()
    a, b = render(ctx, model, data, [left, right], blended=False)
    for world_az in (-1.5, 0.0, 1.5):  # inside the 5 deg overlap centred on the bow
        ca, cb = column_at(left, world_az + 27.5), column_at(right, world_az - 27.5)
        # rows differ slightly off-centre (the frusta are rotated): compare the lower half
        diff = np.abs(a[H // 2:, ca].astype(int) - b[H // 2:, cb].astype(int)).mean()
        assert diff < 12


def test_blend_ramps_sum_to_one_across_the_overlap(ctx, exercise):
    left, right = neighbours()
    world = np.radians(np.linspace(-2.5, 2.5, 101))
    total = blend_ramp(left, world + math.radians(27.5)) + blend_ramp(right, world - math.radians(27.5))
    np.testing.assert_allclose(total, 1.0, atol=1e-12)
    # and in the rendered pixels: in linear light the two blended images add up to the scene
    model, data = exercise
    (sa, sb), (ba, bb) = (render(ctx, model, data, [left, right], blended=flag) for flag in (False, True))
    for world_az in (-2.0, -1.0, 0.0, 1.0, 2.0):
        ca, cb = column_at(left, world_az + 27.5), column_at(right, world_az - 27.5)
        lin = lambda px: (px[H // 2:].astype(float) / 255.0) ** 2.2  # noqa: E731
        summed = lin(ba[:, ca]) + lin(bb[:, cb])
        scene = 0.5 * (lin(sa[:, ca]) + lin(sb[:, cb]))
        assert np.abs(summed - scene).mean() < 0.03


def test_floe_heave_roll_and_pitch_change_its_pixels(ctx, exercise):
    model, data = exercise
    st = data.ice.state
    c = channel(yaw_deg=180.0, pitch_deg=-35.0, eye=[-75.0, 0.0, 20.0])
    # the free floe nearest the spot this channel looks at
    psi = data.ship.eta[5]
    stern = np.array([data.ship.eta[1] - 75 * math.sin(psi), data.ship.eta[0] - 75 * math.cos(psi)])
    spot = stern - 20.0 / math.tan(math.radians(35.0)) * np.array([math.sin(psi), math.cos(psi)])
    free = np.nonzero(st.status == FloeStatus.FREE)[0]
    row = free[np.argmin(np.linalg.norm(st.xy[free] - spot, axis=1))]
    before, = render(ctx, model, data, [c])
    changed = []
    for column, value in ((2, st.heave[row] + 0.4), (4, 0.35), (5, 0.35)):  # heave, roll, pitch
        view = view_of(model, data)
        view.pose[row, column] = value
        after, = render(ctx, model, data, [c], view=view)
        changed.append(int((np.abs(after.astype(int) - before.astype(int)).sum(axis=-1) > 30).sum()))
    assert min(changed) >= 3, changed


def test_bad_channel_config_is_a_clear_error(tmp_path):
    cfg = tmp_path / "bad.toml"
    base = '[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n'
    cases = {
        '[[render.channels]]\nname = "a"\nhfov_deg = 0.0\n': "render.channels.0.hfov_deg = 0.0",
        '[[render.channels]]\nname = "a"\n[[render.channels]]\nname = "a"\n': "channel names must be unique",
        '[[render.channels]]\nname = "a"\noutput = "hologram"\n': "render.channels.0.output = 'hologram'",
    }
    for text, message in cases.items():
        cfg.write_text(base + text)
        r = run_cli("render-snapshot", "--config", str(cfg), "--time", "0")
        assert r.returncode == 2 and message in r.stderr and str(cfg) in r.stderr, r.stderr
        assert "Traceback" not in r.stderr


def test_a_warp_mesh_moves_pixels_as_its_grid_says(ctx, exercise, tmp_path):
    model, data = exercise
    c = channel(yaw_deg=180.0, pitch_deg=-20.0, eye=[-80.0, 0.0, 20.0])
    dx, dy = 10, 6  # px: the grid shows each output pixel the flat image's pixel 10 left of and 6 above it
    rows, cols = 5, 9
    y, x = np.meshgrid(np.linspace(0.0, 1.0, rows), np.linspace(0.0, 1.0, cols), indexing="ij")
    grid = tmp_path / "warp.pfm"
    write_pfm(grid, np.dstack([x - dx / W, y + dy / H]))  # bottom row first, y up
    flat, = render(ctx, model, data, [c])
    warped, = render(ctx, model, data, [c.model_copy(update={"warp": str(grid)})])
    assert np.abs(warped[dy:, dx:].astype(int) - flat[:-dy, :-dx]).max() <= 2
    assert warped[:, :dx].max() == 0 and warped[:dy].max() == 0  # shown from outside the flat image: black
    grid.write_bytes(grid.read_bytes()[:-12])
    with pytest.raises(WarpError, match=r"render.channels \(c\): warp = .*warp.pfm.*bytes of data"):
        render(ctx, model, data, [c.model_copy(update={"warp": str(grid)})])
    config = tmp_path / "node.toml"  # in a config: relative to its folder, checked when it loads
    config.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nthickness = 0.5\n[[render.channels]]\nname = "c"\nwarp = "warp.pfm"\n')
    with pytest.raises(ConfigError, match=r"node.toml: render.channels.0.warp = 'warp.pfm'.*bytes of data"):
        load_config(config)
    write_pfm(grid, np.dstack([x, y]))
    assert load_config(config).render.channels[0].warp == str(grid)
