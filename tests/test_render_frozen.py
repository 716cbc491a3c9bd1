"""A frozen tile on the screen: it gives its rows up, and its floes stay drawn where they
froze, for a renderer that followed the stream and for one that joins late, and for one
that resynchronised after a gap in which the tile thawed and froze again."""
import dataclasses
import math

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet, create_context
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.stream.world_view import WorldView
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.tiles import break_cells, freeze_tile, thaw_tile
from sim_core.scene.switches import FROZEN_FLOE_EVENT
from sim_core.world import snapshot, step

W, H = 256, 160


def channel_over(view: WorldView, k: int, model) -> ChannelSettings:
    """A channel looking astern and down onto placement k's tile from 40 m above it."""
    p, side, ship = view.placements[k], model.scene.side, view.ship
    d_north, d_east = p.corner[1] + 0.5 * side + 23.0 - ship.north, p.corner[0] + 0.5 * side - ship.east
    c, s = math.cos(ship.heading), math.sin(ship.heading)
    return ChannelSettings(name="down", width=W, height=H, yaw_deg=180.0, pitch_deg=-60.0, hfov_deg=60.0,
                           eye=[d_north * c + d_east * s, -d_north * s + d_east * c, 40.0])


def images(ctx, model, channel, views) -> list[np.ndarray]:
    """One renderer fed the views in turn (as the stream feeds it); its image after each."""
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[channel], visibility_m=8000.0)), [channel])
    out = []
    for view in views:
        cs.render(view)
        out.append(cs.targets[0].image().astype(float))
    return out


def blocks(img: np.ndarray, n: int = 8) -> np.ndarray:
    """Mean colour of each n x n block of pixels: where floes and water are, not the snow's grain."""
    h, w = img.shape[0] // n * n, img.shape[1] // n * n
    return img[:h, :w].reshape(h // n, n, w // n, n, -1).mean(axis=(1, 3))


@pytest.fixture(scope="module")
def freezing(tmp_path_factory):
    """A 400 m x 600 m field of 0.5 m ice in 50 m tiles frozen 205 m astern: the view and the
    events of the first step that freezes a tile holding 20 floes or more."""
    cfg = exercise_config(tmp_path_factory.getbasetemp() / "tiles", 400.0, 600.0, 50.0, start_north=-60.0,
                          reverse_distance=205.0)
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    view = WorldView()
    view.apply(snapshot(model, data))
    for _ in range(3000):
        events = step(model, data, 0.1)
        f = events.frozen_floes
        counts = np.bincount(f["placement"], minlength=1) if len(f) else np.zeros(1, int)
        if counts.max() >= 20:
            return model, data, view, events, int(counts.argmax())
        view.apply(events)
    pytest.fail("no tile with 20 floes froze")


def test_a_frozen_tile_stays_on_the_screen_where_its_floes_froze(freezing):
    model, _, view, events, k = freezing
    ctx = create_context()
    rows = view.placements[k]
    rows = np.arange(rows.row_start, rows.row_start + rows.row_count)
    assert np.count_nonzero(view.status[rows] == FloeStatus.FREE) >= 20
    c = channel_over(view, k, model)
    before = dataclasses.replace(view.ship)
    live = WorldView()
    live.apply(view.to_snapshot())
    frozen = WorldView()
    frozen.apply(view.to_snapshot())
    frozen.apply(events)  # the freeze
    frozen.ship = before  # the same eye
    assert k in frozen.frozen and len(frozen.frozen_floes[k]) >= 20
    assert np.all(frozen.status[rows] == FloeStatus.VACANT)  # its rows given up
    bare = WorldView()  # the same, but the tile's floes lost: what a renderer that dropped them shows
    bare.apply(frozen.to_snapshot())
    bare.frozen_floes[k] = np.zeros(0, dtype=FROZEN_FLOE_EVENT)
    late = WorldView()  # a consumer joining after the freeze
    late.apply(frozen.to_snapshot())
    followed_live, followed_frozen = images(ctx, model, c, [live, frozen])
    late_frozen, = images(ctx, model, c, [late])
    bare_img, = images(ctx, model, c, [bare])
    followed_live, followed_frozen, late_frozen, bare_img = (blocks(i) for i in (followed_live, followed_frozen,
                                                                                 late_frozen, bare_img))
    lost = np.abs(followed_live - bare_img).mean()
    assert lost > 3.0  # the tile's floes make a difference on the screen
    # still drawn, where they froze (a floe's snow is its own patch, by its pose entry: the blocks
    # average it out)
    assert np.abs(followed_frozen - followed_live).mean() < 0.05 * lost
    assert np.abs(late_frozen - followed_live).mean() < 0.05 * lost


def test_a_tile_thawed_and_frozen_again_in_a_gap_is_drawn_anew(freezing):
    model, data, _, _, k = freezing  # the world after the freeze (this test changes it: it runs last)
    ctx = create_context()
    view = WorldView()
    view.apply(snapshot(model, data))
    c = channel_over(view, k, model)
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[c], visibility_m=8000.0)), [c])
    cs.render(view)
    before = blocks(cs.targets[0].image().astype(float))
    held = len(view.frozen_floes[k])
    thaw_tile(model.ice, data.ice, k)  # in a gap of the stream: thawed, more of it broken, frozen again
    rows = data.ice.tiles.rows(k)
    intact = rows[data.ice.state.status[rows] == FloeStatus.INTACT]
    break_cells(data.ice, intact[::2], BreakCause.CONTACT)
    freeze_tile(data.ice, k)
    view.apply(snapshot(model, data))  # the resynchronisation
    assert len(view.frozen_floes[k]) > held
    cs.render(view)
    after = blocks(cs.targets[0].image().astype(float))
    fresh = WorldView()
    fresh.apply(snapshot(model, data))
    fresh_img, = images(ctx, model, c, [fresh])
    changed = np.abs(after - before).mean()
    assert changed > 3.0  # the cells broken in the gap show
    assert np.abs(after - blocks(fresh_img)).mean() < 0.05 * changed  # as a renderer starting now draws them
