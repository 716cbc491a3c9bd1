"""The world's published contract: events and snapshots agree (a floe at rest is not sent
again), live rows keep their numbers and a frozen tile's rows go to the next tile, a thawed
tile's floes come back where they froze, and refused orders are counted and raise an alarm."""
import dataclasses
import math

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.exercise.order_refusals import REFUSED_ALARM, OrderRefusals
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.stream.world_view import WorldView
from sim_core.fracture.tile_template import FractureSettings, build_tile
from sim_core.frames.hull_contour import waterline_contour
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.model import compile_ice_model
from sim_core.ice.step import HullMotion, ice_step
from sim_core.ice.tiles import break_cells, freeze_tile, new_ice_data, place_tile, reclaim_rows, thaw_tile
from sim_core.ship.model import OrderRejection
from sim_core.world import Controls, snapshot, step


@pytest.fixture(scope="module")
def small_world(tmp_path_factory):
    """A 400 m x 600 m field of 0.5 m ice in 50 m tiles, freezing tiles 205 m astern."""
    cfg = exercise_config(tmp_path_factory.getbasetemp() / "tiles", 400.0, 600.0, 50.0, start_north=-60.0,
                          reverse_distance=205.0)
    return build_world(cfg, None), cfg


def _assert_same_state(late: WorldView, view: WorldView) -> None:
    assert late.placements == view.placements and late.frozen == view.frozen
    rows = view.live_rows()
    np.testing.assert_array_equal(late.live_rows(), rows)
    np.testing.assert_array_equal(late.status[rows], view.status[rows])
    np.testing.assert_allclose(late.pose[rows], view.pose[rows])
    np.testing.assert_array_equal(late.cause[rows], view.cause[rows])
    np.testing.assert_array_equal(late.crack[rows], view.crack[rows])
    assert late.frozen_floes.keys() == view.frozen_floes.keys() == view.frozen
    for k, floes in view.frozen_floes.items():
        np.testing.assert_array_equal(late.frozen_floes[k], floes)
    assert late.frozen_cracks.keys() == view.frozen_cracks.keys()
    for k, cracks in view.frozen_cracks.items():
        np.testing.assert_array_equal(late.frozen_cracks[k], cracks)


def test_events_applied_step_by_step_equal_a_snapshot(small_world):
    model, cfg = small_world
    data = start_world(model, cfg)
    view = WorldView()
    view.apply(snapshot(model, data))
    frozen_seen, placed_cells, sent = 0, 0, []  # (rows sent, free rows) at each check
    for n in range(1, 2501):  # 250 s: tiles placed, cells broken, tiles frozen astern, the field left
        events = step(model, data, 0.1)
        frozen_seen += len(events.frozen)
        placed_cells += int(events.placed.row_count.sum())
        view.apply(events)
        if n in (1500, 2500):  # with the ship in the field, and after it has left
            late = WorldView()  # a consumer joining now
            late.apply(snapshot(model, data))
            _assert_same_state(late, view)
            st = data.ice.state
            live = data.live_rows
            free = np.count_nonzero(st.status[live] == FloeStatus.FREE)
            assert late.take_changes().broken.size == free
            sent.append((len(events.floe_rows), free))
            assert events.floes_frozen == data.ice.frozen.count == sum(len(f) for f in view.frozen_floes.values())
    assert frozen_seen > 0 and events.floes_frozen > 0 and events.seq == 2500
    moving, free = sent[0]  # in the field, the floes at rest were not sent again, yet the views agreed
    assert 0 < moving < 0.5 * free
    assert any(len(c) for c in view.frozen_cracks.values())  # tiles froze with cracked cells, and they compared
    assert view.ship.time == pytest.approx(data.time) and view.ship.north == data.ship.eta[0]
    assert data.ice.state.n < placed_cells  # frozen tiles' rows went to later tiles


def test_live_rows_keep_their_cells_and_frozen_rows_go_to_the_next_tile():
    tile = build_tile(0.5, 3, FractureSettings(tile_side=40.0, colliders="sphere"))
    model = compile_ice_model([tile])
    data = new_ice_data(model, waterline_contour(150.0, 24.0), 0.1)
    n = tile.n_cells
    first = place_tile(model, data, 0, (0.0, 0.0))
    second = place_tile(model, data, 0, (40.0, 0.0), 1)
    assert (first, second) == (0, 1)
    kept = data.tiles.rows(second)
    gcell = data.state.gcell[kept].copy()
    freeze_tile(data, first)
    assert len(data.tiles.rows(first)) == 0 and data.frozen.count == 0  # nothing broken: no record
    third = place_tile(model, data, 0, (80.0, 0.0))
    assert data.tiles.rows(third)[0] == 2 * n  # the first's rows are not given while its bodies leave
    far = HullMotion(np.array([0.0, -9000.0]), 0.0, np.zeros(2), 0.0)
    while data.contacts.swaps_pending:
        ice_step(model, data, (far,), 1 / 30)
    reclaim_rows(data)
    assert data.state.count(FloeStatus.VACANT) == n
    fourth = place_tile(model, data, 0, (120.0, 0.0))
    assert data.tiles.rows(fourth)[0] == 0 and data.state.n == 3 * n  # the first's rows, reused
    thaw_tile(model, data, first)
    assert data.tiles.rows(first)[0] == 3 * n and data.state.n == 4 * n
    np.testing.assert_array_equal(data.state.gcell[data.tiles.rows(first)], np.arange(n))
    np.testing.assert_array_equal(data.state.tile[data.tiles.rows(fourth)], fourth)
    np.testing.assert_array_equal(data.state.gcell[kept], gcell)  # a live tile's rows never moved
    np.testing.assert_array_equal(data.state.tile[kept], second)


def test_thawed_floes_come_back_to_life_where_they_froze():
    tile = build_tile(0.5, 5, FractureSettings(tile_side=40.0, colliders="sphere"))
    model = compile_ice_model([tile])
    data = new_ice_data(model, waterline_contour(150.0, 24.0), 0.1)
    rows = data.tiles.rows(place_tile(model, data, 0, (0.0, 0.0)))
    st = data.state
    loose = rows[np.abs(st.home[rows, 0] - 20.0) < 6.0]  # a lane through the middle
    break_cells(data, loose, BreakCause.HULL)
    data.contacts.set_velocity(data.state, loose, np.tile([0.0, 0.3], (len(loose), 1)), np.zeros(len(loose)))
    far = HullMotion(np.array([0.0, -9000.0]), 0.0, np.zeros(2), 0.0)
    for _ in range(30):
        ice_step(model, data, (far,), 1 / 30)
    moved = st.xy[loose].copy()
    assert np.abs(moved - st.home[loose]).max() > 0.05  # they drifted before freezing
    yaw = st.yaw[loose].copy()
    freeze_tile(data, 0)
    assert np.all(st.status[loose] == FloeStatus.FROZEN) and data.frozen.count == len(loose)
    assert st.count(FloeStatus.FREE) == 0
    np.testing.assert_array_equal(np.sort(data.frozen[0]["cell"]), loose - rows[0])
    thaw_tile(model, data, 0)
    back = data.tiles.rows(0)[loose - rows[0]]  # the same cells, in the tile's new rows
    assert np.all(st.status[back] == FloeStatus.FREE) and data.frozen.count == 0
    np.testing.assert_array_equal(st.xy[back], moved)  # at the poses they froze with
    np.testing.assert_array_equal(st.yaw[back], yaw)
    np.testing.assert_array_equal(st.cause[back], BreakCause.HULL)
    assert st.count(FloeStatus.FREE) == len(loose)
    # and alive again: the contact space moves them
    data.contacts.set_velocity(data.state, back, np.tile([0.0, 0.3], (len(back), 1)), np.zeros(len(back)))
    ice_step(model, data, (far,), 1 / 30)
    assert np.abs(st.xy[back] - moved).max() > 1e-3


def test_rejected_orders_are_published_counted_and_alarmed(small_world):
    model, cfg = small_world
    data = start_world(model, cfg)
    events = step(model, data, 0.1, Controls(rudder=math.radians(60.0), telegraph="warp_nine"))
    assert [(r.order, r.refused) for r in events.rejected] == [("rudder", False), ("telegraph", True)]
    refusals = OrderRefusals()
    refused = OrderRejection("telegraph", True, "unknown telegraph position 'warp_nine' rejected")
    clamped = OrderRejection("rudder", False, "rudder order 60.0 deg clamped to the 35 deg limit")
    assert refusals.note((clamped,) * 5, 0.0) == []  # clamped orders are obeyed: no alarm
    assert refusals.note((refused,), 0.0) == [] and refusals.note((refused,), 1.0) == []
    raised = refusals.note((refused,), 2.0)
    assert [(a.number, a.active) for a in raised] == [(REFUSED_ALARM["telegraph"], True)]
    assert raised[0].text == "engine orders refused repeatedly"  # fits ALR's text field; the reason is logged
    assert refusals.note((refused,), 3.0) == []  # raised once
    cleared = refusals.note((), 20.0)
    assert [(a.number, a.active) for a in cleared] == [(REFUSED_ALARM["telegraph"], False)]
    assert refusals.counts == {"rudder clamped": 5, "telegraph refused": 4}


def test_view_blends_between_the_two_latest_states(small_world):
    model, cfg = small_world
    data = start_world(model, cfg)
    view = WorldView()
    for _ in range(400):
        view.apply(step(model, data, 0.1))
    before_ship, before = view.ship, view.pose.copy()
    events = step(model, data, 0.5, Controls(rudder=math.radians(35.0)))
    events = dataclasses.replace(events, ice_offset=(2.0, -1.0))  # as if the field had drifted that far
    view.apply(events)
    after = view.pose.copy()
    rows = events.floe_rows
    view.blend(0.5)
    assert view.ship.north == pytest.approx(0.5 * (before_ship.north + events.ship.north))
    np.testing.assert_allclose(view.ice_offset, [1.0, -0.5])  # the field's frame in between too
    np.testing.assert_allclose(view.pose[rows, :3], 0.5 * (before[rows, :3] + after[rows, :3]))
    assert np.abs(after[rows, :2] - before[rows, :2]).max() > 0.01  # something did move
    view.blend(1.0)
    assert view.ship == events.ship and tuple(view.ice_offset) == events.ice_offset
    np.testing.assert_array_equal(view.pose, after)
    view.blend(0.25)
    nxt = step(model, data, 0.1)
    view.apply(nxt)  # a new step starts from the true state, not the blended one
    np.testing.assert_array_equal(view.pose[nxt.floe_rows], nxt.floe_pose)
