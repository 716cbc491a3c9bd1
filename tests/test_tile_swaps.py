"""Tile swaps off the critical path: tiles prepared ahead switch in (and thaw) with the same
physics as tiles built at their switch, and floes that leave the simulation and come back
keep their pose and momentum."""
import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.node.world_setup import build_world, start_world
from sim_core.fracture.tile_template import FractureSettings, build_tile
from sim_core.ice.chipmunk_bodies import TileBodies
from sim_core.ice.contact_swaps import REMOVAL_OWN_COST
from sim_core.frames.hull_contour import waterline_contour
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.model import compile_ice_model
from sim_core.ice.step import HullMotion, ice_step
from sim_core.ice.tiles import (
    break_cells,
    broken_counts,
    freeze_tile,
    new_ice_data,
    place_tile,
    reclaim_rows,
    thaw_tile,
)
from sim_core.world import Controls, KinematicPose, step


def _transit(tmp_path, prepare_ahead: float, steps: int = 900):
    """The default ship steaming north through a 400 m x 600 m field of 50 m tiles."""
    cfg = exercise_config(tmp_path / "tiles", 400.0, 600.0, 50.0, start_north=-60.0, reverse_distance=205.0,
                          prepare_ahead=prepare_ahead)
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    placed_at_start = None
    for k in range(steps):
        events = step(model, data, 0.1)
        if k == 0:
            placed_at_start = len(data.scene.placement)
    return data, placed_at_start, events


def test_prepared_tiles_switch_in_with_the_same_physics_as_tiles_built_at_the_switch(tmp_path):
    ahead, at_start, events = _transit(tmp_path, prepare_ahead=60.0)
    built, _, _ = _transit(tmp_path, prepare_ahead=0.0)
    assert len(ahead.scene.placement) > at_start and events.floes_frozen > 0  # tiles placed, thawed none, frozen
    assert ahead.late_switches == 0  # every switch found its tile built
    a, b = ahead.ice.state, built.ice.state
    assert a.n == b.n
    for cause in (BreakCause.HULL, BreakCause.CONTACT):
        np.testing.assert_array_equal(np.nonzero(a.cause == cause)[0], np.nonzero(b.cause == cause)[0])
    assert np.count_nonzero(a.cause == BreakCause.CONTACT) > 0
    np.testing.assert_array_equal(a.status, b.status)
    np.testing.assert_array_equal(a.xy, b.xy)  # bit for bit: contacts are read in a fixed order
    assert a.resting.any()  # floes at rest astern left the dynamic set, the same ones in both runs
    np.testing.assert_array_equal(a.resting, b.resting)


def _there_and_back(tmp_path, prepare_ahead: float) -> tuple:
    """The hull driven north at 4 m/s through a 400 m x 600 m field of 50 m tiles (tiles
    freeze 205 m astern), then astern back down its channel: the frozen tiles thaw."""
    cfg = exercise_config(tmp_path / "tiles", 400.0, 600.0, 50.0, start_north=-60.0, reverse_distance=205.0,
                          prepare_ahead=prepare_ahead)
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    north, east, thawed, dt = data.ship.eta[0], data.ship.eta[1], 0, 0.1
    for k in range(2300):
        surge = 4.0 if k < 1250 else -4.0
        north += surge * dt
        events = step(model, data, dt, Controls(kinematic=KinematicPose(north, east, 0.0, surge)))
        thawed += len(events.thawed)
    return data, thawed


def test_thawed_tiles_take_the_same_rows_prepared_or_not(tmp_path):
    ahead, thawed = _there_and_back(tmp_path, prepare_ahead=60.0)
    built, _ = _there_and_back(tmp_path, prepare_ahead=0.0)
    assert thawed > 0 and ahead.ice.frozen.count > 0
    a, b = ahead.ice.state, built.ice.state
    assert a.n == b.n
    np.testing.assert_array_equal(a.status, b.status)  # rows are taken at the switch, in step order
    np.testing.assert_array_equal(a.cause, b.cause)
    np.testing.assert_array_equal(a.xy, b.xy)
    np.testing.assert_array_equal(broken_counts(ahead.ice), broken_counts(built.ice))


@pytest.mark.parametrize("settle", [True, False], ids=["after-leaving", "while-leaving"])
def test_floes_that_leave_and_reenter_keep_pose_and_momentum(settle):
    tile = build_tile(0.5, 5, FractureSettings(tile_side=40.0, colliders="sphere"))
    model = compile_ice_model([tile])
    data = new_ice_data(model, waterline_contour(150.0, 24.0), 0.1)
    far = HullMotion(np.array([0.0, -9000.0]), 0.0, np.zeros(2), 0.0)
    rows = data.tiles.rows(place_tile(model, data, 0, (0.0, 0.0)))
    st = data.state
    loose = rows[np.abs(st.home[rows, 0] - 20.0) < 6.0]
    break_cells(data, loose, BreakCause.HULL)
    rng = np.random.default_rng(3)
    data.contacts.set_velocity(st, loose, rng.uniform(-0.2, 0.2, (len(loose), 2)), rng.uniform(-0.05, 0.05, len(loose)))
    for _ in range(20):
        ice_step(model, data, (far,), 1 / 30)
    pose = st.xy[loose].copy(), st.yaw[loose].copy()
    momentum = st.vel[loose].copy(), st.yaw_rate[loose].copy()
    assert np.abs(momentum[0]).max() > 0.01
    freeze_tile(data, 0)
    assert np.all(st.status[loose] == FloeStatus.FROZEN)
    if settle:  # the tile's bodies leave the engine over the following steps
        while data.contacts.swaps_pending:
            ice_step(model, data, (far,), 1 / 30)
        reclaim_rows(data)
        assert np.all(st.status[rows] == FloeStatus.VACANT)  # the tile's rows are given back
    else:
        np.testing.assert_array_equal(st.xy[loose], pose[0])  # frozen floes do not move
    thaw_tile(model, data, 0)
    back = data.tiles.rows(0)[loose - rows[0]]  # the same cells, in the tile's rows now
    assert np.all(st.status[back] == FloeStatus.FREE)
    while data.contacts.swaps_pending:
        data.contacts.step(1e-9)  # back into the engine, time all but still
    data.contacts.read_free(st)
    np.testing.assert_allclose(st.xy[back], pose[0], atol=1e-9)
    np.testing.assert_allclose(st.yaw[back], pose[1], atol=1e-9)
    np.testing.assert_allclose(st.vel[back], momentum[0], rtol=1e-6)
    np.testing.assert_allclose(st.yaw_rate[back], momentum[1], rtol=1e-6)


def test_a_freeze_takes_its_tile_out_within_the_removal_budget(monkeypatch):
    """Each removal costs Chipmunk a walk over every cached contact and about
    ``REMOVAL_OWN_COST`` such visits besides: a freezing tile among many contacts leaves over
    several steps, each removing no more than ``swap_removal_work`` allows for the contacts
    the space held, and in the end nothing of it is left in the space."""
    tile = build_tile(0.5, 5, FractureSettings(tile_side=100.0, colliders="sphere"))
    model = compile_ice_model([tile])
    data = new_ice_data(model, waterline_contour(150.0, 24.0), 0.1)
    far = HullMotion(np.array([0.0, -9000.0]), 0.0, np.zeros(2), 0.0)
    rows = data.tiles.rows(place_tile(model, data, 0, (0.0, 0.0)))
    loose = rows[::2]
    break_cells(data, loose, BreakCause.HULL)  # half the cells loose among the rest, pushing: many contacts
    rng = np.random.default_rng(5)
    data.contacts.set_velocity(data.state, loose, rng.uniform(-0.5, 0.5, (len(loose), 2)), np.zeros(len(loose)))
    for _ in range(5):
        ice_step(model, data, (far,), 1 / 30)
    removed = []
    original = TileBodies.remove
    monkeypatch.setattr(TileBodies, "remove", lambda self, space, offsets: removed.append(
        original(self, space, offsets)) or removed[-1])
    space, work = data.contacts, model.settings.swap_removal_work
    floes = int((data.state.status[rows] == FloeStatus.FREE).sum())  # a body and a shape each, a cell one shape
    freeze_tile(data, 0)
    per_step = []
    while space.swaps_pending:
        allowed = max(8, work // (space._arbiters + REMOVAL_OWN_COST))
        removed.clear()
        ice_step(model, data, (far,), 1 / 30)
        per_step.append((sum(removed), allowed))
    assert space._arbiters == 0  # the tile's contacts went with it
    assert len(per_step) > 2 and per_step[0][1] < 800  # the contacts held the share below the count cap
    assert all(n <= allowed + 2 for n, allowed in per_step)  # (a chunk is whole cells: up to 3 objects)
    assert sum(n for n, _ in per_step) == len(rows) + floes  # every object of the tile
