"""Scene management (paper §2.4, §3.4): quadtree detection, swaps, reverse replacement."""
import math

import numpy as np
import pytest

from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, start_world
from sim_core.frames.hull_contour import waterline_contour
from sim_core.frames.ship_frame import ship_to_world
from sim_core.ice.floes import FloeStatus
from sim_core.scene.quadtree import detection_radius, tile_under, tiles_near, tiles_near_brute_force
from sim_core.scene.scene import SceneSettings, TileState, compile_scene, new_scene_data, update_scene
from sim_core.world import step

L, BEAM, B = 150.0, 24.0, 100.0
CONTOUR = waterline_contour(L, BEAM)


def scene(n: int, **settings):
    return compile_scene(SceneSettings(**settings), np.zeros((n, n), np.uint8), np.array([0.5]),
                         [np.array([0])], B, L)


def test_detection_radius_covers_the_tile_and_the_corner_buffer():
    """Any point of a tile lies within R_T - L/10 of its centre (the fragmentation buffer
    reaches its corners and no farther), so a contour point anywhere on a tile detects it
    with L/10 to spare: for B = 100 m, L = 150 m that is 85.7 m."""
    radius = detection_radius(B, L)
    assert radius == pytest.approx(85.71, abs=0.01)
    rng = np.random.default_rng(3)
    pts = rng.uniform(0.0, B, (2000, 2))
    reach = np.hypot(*(pts - B / 2).T)
    assert reach.max() <= radius - L / 10 and reach.max() > 0.97 * (radius - L / 10)
    assert 0 in tiles_near(np.array([[B - 1e-6, B - 1e-6]]), radius - L / 10 + 1e-6, 4, 4, B)
    assert 0 not in tiles_near(np.array([[B + 1e-3, B + 1e-3]]), radius - L / 10, 4, 4, B)
    assert scene(4).radius == radius


@pytest.mark.parametrize("n", [64, 640])
def test_quadtree_returns_what_brute_force_returns(n):
    rng = np.random.default_rng(n)
    side = n * B
    for _ in range(40):
        north, east = rng.uniform(-300, side + 300, 2)  # some poses hang over the field's edge
        pts = ship_to_world(CONTOUR, north, east, rng.uniform(0, 2 * math.pi))
        radius = detection_radius(B, L)
        np.testing.assert_array_equal(tiles_near(pts, radius, n, n, B), tiles_near_brute_force(pts, radius, n, n, B))
    # a non-square, non-power-of-two grid
    pts = ship_to_world(CONTOUR, 250.0, 1250.0, 0.3)
    np.testing.assert_array_equal(tiles_near(pts, 85.0, 13, 5, B), tiles_near_brute_force(pts, 85.0, 13, 5, B))


def test_corner_first_approach_detected_before_contact_traditional_test_late():
    """Ship heading north-east at the south-west corner of tile (5, 5) (paper Fig. 8-11)."""
    target = 5 * 64 + 5
    psi = math.radians(45.0)
    first = {}
    for k in range(4000):
        d = -250.0 + 0.25 * k  # distance of the midship past the corner, along the track
        north = east = 500.0 + d / math.sqrt(2)
        pts = ship_to_world(CONTOUR, north, east, psi)
        if "detected" not in first and target in tiles_near(pts, detection_radius(B, L), 64, 64, B):
            first["detected"] = d
        if "contour inside" not in first and any(tile_under(p, 64, 64, B) == target for p in pts):
            first["contour inside"] = d
        if "origin inside" not in first and tile_under(np.array([east, north]), 64, 64, B) == target:
            first["origin inside"] = d
    assert first["detected"] < first["contour inside"] < first["origin inside"]
    # the bow is inside the tile half a ship length before the traditional test reacts
    assert first["origin inside"] - first["contour inside"] > 0.4 * L


def zigzag_poses(length: float, step: float = 2.0):
    """A 10 km zig-zag: heading swings +-60 deg about north-east over 1 km, turning at
    most 3 deg per 2 m, and doubles back twice so frozen tiles are met again."""
    north, east, psi = 1500.0, 1500.0, 0.0
    travelled = 0.0
    while travelled < length:
        base = math.radians(45.0) if (travelled // 3500) % 2 == 0 else math.radians(225.0)
        want = base + math.radians(60.0) * math.sin(2 * math.pi * travelled / 1000.0)
        turn = (want - psi + math.pi) % (2 * math.pi) - math.pi
        psi += max(-math.radians(3.0), min(math.radians(3.0), turn))
        north += step * math.cos(psi)
        east += step * math.sin(psi)
        travelled += step
        yield north, east, psi


@pytest.mark.parametrize("detection", ["contour", "origin"])
def test_no_contour_point_touches_unbreakable_ice_in_10km_zigzag(detection):
    model = scene(96, detection=detection, reverse_distance=700.0)
    data = new_scene_data(model)
    touched, frozen, thawed = 0, 0, 0
    for north, east, psi in zigzag_poses(10_000.0):
        pts = ship_to_world(CONTOUR, north, east, psi)
        up = update_scene(model, data, pts, np.array([east, north]))
        frozen += len(up.freeze)
        thawed += len(up.thaw)
        tiles = [tile_under(p, 96, 96, B) for p in pts]
        touched += sum(1 for t in tiles if t >= 0 and data.tile_state[t] != TileState.BREAKABLE)
        assert len(data.live) < 100  # reverse replacement bounds the live tiles
    if detection == "contour":
        assert touched == 0
        assert frozen > 50 and thawed > 0  # the track doubled back over frozen tiles
    else:
        assert touched > 1000  # the traditional test lets the bow into intact tiles
    assert set(np.unique(data.tile_state)) <= set(TileState)


def test_reverse_distance_shorter_than_the_ship_is_rejected():
    with pytest.raises(ValueError, match="reverse_distance"):
        scene(8, reverse_distance=150.0)


@pytest.fixture(scope="module")
def transits(tmp_path_factory):
    """Straight transits at full ahead through 50 m tiles of 0.5 m ice, 520 m into the field,
    with and without reverse replacement (freezing beyond 205 m)."""
    base = load_config()
    out = {}
    for reverse in (True, False):
        cfg = base.model_copy(update={
            "fracture": base.fracture.model_copy(update={"tile_side": 50.0}),
            "ice_field": base.ice_field.model_copy(update={"width": 400.0, "height": 1000.0}),
            "scene": SceneSettings(reverse_replacement=reverse, reverse_distance=205.0),
            "paths": base.paths.model_copy(update={"cache_dir": str(tmp_path_factory.getbasetemp() / "tiles")}),
        })
        model = build_world(cfg, None)
        data = start_world(model, cfg)
        series = []
        while data.ship.eta[0] < 520.0:
            ev = step(model, data, 0.1)
            st = data.ice.state
            series.append((data.ship.eta[0], st.count(FloeStatus.FREE), data.ice.frozen.count,
                           len(ev.broken_by_hull)))
        out[reverse] = (model, data, np.array(series))
    return out


def peak_live(series, north0, north1):
    """Most live fragments while the midship went from north0 to north1, m."""
    return series[(series[:, 0] >= north0) & (series[:, 0] < north1), 1].max()


def test_live_fragments_grow_without_reverse_replacement_and_stay_bounded_with_it(transits):
    grow = transits[False][2]
    bounded = transits[True][2]
    assert peak_live(grow, 360, 520) > 1.25 * peak_live(grow, 200, 360)
    assert peak_live(bounded, 360, 520) < 1.1 * peak_live(bounded, 200, 360)
    assert bounded[:, 1].max() < 0.6 * grow[:, 1].max()
    assert grow[-1, 2] == 0  # nothing frozen without reverse replacement


def test_frozen_channel_stays_in_the_scene(transits):
    model, data, series = transits[True]
    xy = data.ice.frozen.records()["xy"]
    assert series[-1, 2] > 100 and len(xy) == series[-1, 2]
    # the frozen floes are the broken channel astern: near the track, south of the ship
    assert np.all(xy[:, 1] < data.ship.eta[0] - 150.0)
    track = (model.scene.nx // 2 + 0.5) * model.scene.side  # the start_world default
    assert np.abs(np.median(xy[:, 0]) - track) < 10.0
    assert np.all(np.isfinite(xy))
    assert (data.scene.tile_state == TileState.FROZEN).sum() >= 2


def test_world_step_reports_swaps_and_breaking(transits):
    model, data, series = transits[True]
    assert series[:, 3].sum() > 100  # cells broken by the hull, reported per step
    assert 2.0 < data.ship.nu[0] < 6.0  # the ship made way through the ice under its own power
    assert data.scene.placement  # tiles were placed in the ice world
