"""The own ship and the other vessels in the channels (EGL offscreen): the generated hull
follows the contour the ice feels, a ship file's GLB replaces it, bridge eyes by name, and
each row of ``WorldView.traffic`` drawn as a ship where its position says."""
import math
from datetime import datetime

import numpy as np
import pytest
from test_render import H, W, channel, render, view_of

from bridge_node.node.config import load_ship
from bridge_node.render.camera import channel_camera
from bridge_node.render.settings import eye_point
from bridge_node.render.ship_mesh import (
    CRANE,
    EYE_ABOVE_FLOOR_M,
    MAST,
    ShipModelError,
    default_ship,
    glb_bytes,
    ship_triangles,
)
from bridge_node.render.ship_mesh import load_ship as ship_mesh
from bridge_node.stream.world_view import TRAFFIC_DTYPE
from sim_core.frames.hull_contour import waterline_contour

FREEBOARD = 9.0


@pytest.fixture(scope="module")
def particulars():
    return load_ship("polar_cargo")


def test_generated_hull_stands_on_the_contour_and_bridge_under_the_eye(particulars):
    contour = waterline_contour(particulars.length, particulars.beam)
    mesh = default_ship(particulars, contour, FREEBOARD)
    at_waterline = mesh.vertices[np.abs(mesh.vertices[:, 2]) < 1e-9][:, :2]
    # every waterline vertex is a contour point, and every contour point is there: the bow is where the contour says
    d = np.linalg.norm(at_waterline[:, None] - contour[None], axis=-1)
    assert d.min(axis=1).max() < 1e-6 and d.min(axis=0).max() < 1e-6
    assert abs(at_waterline[:, 0].max() - particulars.length / 2) < 1e-6
    bx, bz = particulars.look.bridge_eye
    house = mesh.vertices[np.abs(mesh.vertices[:, 0] - bx) <= 2.0 + 1e-6]
    assert abs(house[:, 2].max() - (bz - EYE_ABOVE_FLOOR_M)) < 1e-6  # the bridge deck under the eye
    assert eye_point("bridge", [bx, bz], particulars.beam) == (bx, 0.0, bz)
    port, stbd = (eye_point(w, [bx, bz], particulars.beam) for w in ("port_wing", "starboard_wing"))
    assert port[1] < -particulars.beam / 2 < particulars.beam / 2 < stbd[1]  # looking down the ship's sides


def test_the_deck_gear_leaves_the_sea_in_view_ahead(particulars):
    """SOLAS V/22.1.1: from the conning position the sea is not hidden more than two ship
    lengths or 500 m (the less) ahead of the bow, 10 deg either side; V/22.1.2: no blind
    sector of cargo gear forward of the beam wider than 10 deg."""
    contour = waterline_contour(particulars.length, particulars.beam)
    mesh = default_ship(particulars, contour, FREEBOARD)
    bx, bz = particulars.look.bridge_eye
    colour = np.repeat(mesh.visual.face_colors[:, :3].astype(float) / 255.0, 3, axis=0)
    points = mesh.vertices[mesh.faces].reshape(-1, 3)
    gear = np.isclose(colour, MAST, atol=0.01).all(axis=1) | np.isclose(colour, CRANE, atol=0.01).all(axis=1)
    ahead = (points[:, 0] > bx + 2.5) & (np.abs(points[:, 1]) <= (points[:, 0] - bx) * math.tan(math.radians(10.0)))
    hull = points[ahead & ~gear]
    assert len(hull) and hull[:, 2].max() < bz
    reach = bx + (hull[:, 0] - bx) * bz / (bz - hull[:, 2])  # where the sight line over each point meets the sea
    blind = reach.max() - contour[:, 0].max()
    assert 0.0 < blind <= min(2.0 * particulars.length, 500.0), blind
    forecastle = points[:, 0] > 0.38 * particulars.length
    mast = points[np.isclose(colour, MAST, atol=0.01).all(axis=1) & forecastle]  # the foremast and its signal yard
    bearing = np.degrees(np.arctan2(mast[:, 1], mast[:, 0] - bx))
    assert bearing.max() - bearing.min() <= 10.0
    assert gear.any() and (colour[:, 0] > 0.7).any()  # the gear is there


def test_a_ship_files_glb_replaces_the_generated_hull(tmp_path, particulars):
    contour = waterline_contour(particulars.length, particulars.beam)
    generated = default_ship(particulars, contour, FREEBOARD)
    glb = tmp_path / "ship.glb"
    glb.write_bytes(glb_bytes(generated))
    own = particulars.model_copy(update={"look": particulars.look.model_copy(update={"model_glb": str(glb)})})
    loaded = ship_mesh(own, contour, FREEBOARD)
    a, b = ship_triangles(generated), ship_triangles(loaded)
    assert a.shape == b.shape and np.allclose(a[:, :6], b[:, :6], atol=1e-4) and np.allclose(a[:, 6:], b[:, 6:], atol=0.01)
    for bad in (tmp_path / "missing.glb", tmp_path / "ship.obj"):
        wrong = own.model_copy(update={"look": own.look.model_copy(update={"model_glb": str(bad)})})
        with pytest.raises(ShipModelError, match=r"ships/polar_cargo.toml: look.model_glb = .*\.glb"):
            ship_mesh(wrong, contour, FREEBOARD)


def test_each_traffic_row_is_drawn_as_a_ship_where_it_is(ctx, exercise):
    model, data = exercise
    c = channel(yaw_deg=180.0, pitch_deg=-10.0, eye=[-80.0, 0.0, 20.0])  # astern, down the broken channel
    view = view_of(model, data)
    s = view.ship
    base, = render(ctx, model, data, [c], view=view)
    for bearing in (-15.0, 10.0):  # from astern, + to port of the view's centre as seen looking aft
        view = view_of(model, data)
        az = s.heading + math.pi + math.radians(bearing)
        x, y = s.east + 400 * math.sin(az), s.north + 400 * math.cos(az)
        rows = [(7, x, y, az, 5.0, 120.0, 20.0),  # heading away: its silhouette symmetric about its position
                (8, s.east + 400 * math.sin(s.heading), s.north + 400 * math.cos(s.heading), 0.0, 5.0, 0.0, 0.0)]
        view.traffic = np.array(rows, dtype=TRAFFIC_DTYPE)  # the second ahead: out of this channel's view
        img, = render(ctx, model, data, [c], view=view)
        changed = np.abs(img.astype(int) - base).sum(axis=-1) > 40
        cols = np.nonzero(changed)[1]
        assert changed.sum() > 20, changed.sum()
        clip = channel_camera(c, c.eye, s.north, s.east, s.heading, 20_000.0).view_proj @ [x, y, 0.0, 1.0]
        expected = (clip[0] / clip[3] + 1) / 2 * W
        assert abs(cols.mean() - expected) < 6, (cols.mean(), expected)
        horizon = (1 - math.tan(math.radians(-c.pitch_deg)) / math.tan(c.vfov() / 2)) / 2 * H
        assert np.nonzero(changed)[0].max() > horizon + 2  # its hull on the sea, below the horizon
    empty = view_of(model, data)
    empty.traffic = np.zeros(0, dtype=TRAFFIC_DTYPE)
    assert np.array_equal(render(ctx, model, data, [c], view=empty)[0], base)


def test_at_night_a_vessel_shows_the_sidelight_of_its_side_facing_the_eye(ctx, exercise):
    model, data = exercise
    c = channel()  # ahead, from the bridge
    night = datetime.fromisoformat("2026-12-21T22:00:00+00:00")  # polar night
    seen = {}
    for turn in (90.0, -90.0):  # crossing ahead to starboard (its starboard side towards us), then to port
        view = view_of(model, data)
        s = view.ship
        x, y = s.east + 500 * math.sin(s.heading), s.north + 500 * math.cos(s.heading)
        view.traffic = np.array([(9, x, y, s.heading + math.radians(turn), 5.0, 100.0, 16.0)], dtype=TRAFFIC_DTYPE)
        img = render(ctx, model, data, [c], view=view, start_utc=night)[0].astype(int)
        r, g = img[..., 0], img[..., 1]
        seen[turn] = ((g > r + 60).sum(), (r > g + 60).sum())  # green pixels, red pixels
    assert seen[90.0][0] > 3 and seen[90.0][1] == 0, seen  # green: its starboard light
    assert seen[-90.0][1] > 3 and seen[-90.0][0] == 0, seen  # red: its port light
