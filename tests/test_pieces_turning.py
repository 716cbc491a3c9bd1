"""Pieces turning against the bow (issue 28, item 1): a piece the bow strikes turns about its
far edge until it lies parallel to the hull's surface, over its own length of the surface's
advance across the waterline, sin(alpha) of the ship's (``sim_core.ice.turning``), then
slides under the hull to the submerged pose over another length, with no jump on the way;
the planar physics is the same as when pieces go under at once."""
import dataclasses
import math

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.node.world_setup import build_world, start_world
from sim_core.ice.floes import FloeStatus
from sim_core.ice.turning import PUSHED_DOWN_TILT, turn_angle
from sim_core.ship.resistance import bow_normal_angle
from sim_core.world import step

DT = 1.0 / 30.0
STEPS = 600  # 20 s


@pytest.mark.parametrize("psi", [0.4, 0.75, 1.2])
def test_the_turn_is_the_inverse_of_the_hulls_advance(psi):
    theta = np.linspace(0.0, psi, 25)
    advanced = np.sin(theta) / math.tan(psi) + 1.0 - np.cos(theta)  # x / d with the near edge on the hull
    assert [turn_angle(float(a), psi) for a in advanced] == pytest.approx(theta, abs=1e-6)
    assert turn_angle(1.0, psi) == psi and turn_angle(1.5, psi) == psi and turn_angle(-0.1, psi) == 0.0
    assert advanced[-1] == pytest.approx(1.0)  # parallel to the hull after one piece length


def _run(tmp_path_factory, name: str, at_once: bool = False):
    """A 400 m x 600 m field of 0.5 m ice, the ship steaming into it for 20 s (``at_once``:
    its bow's surface angle 0, so that pieces go under at once): per step the rows turning
    (not yet sliding) and their (tilt, depth of the centre below its draft, length); per
    piece its roll once done and the ship's north when it started, lay parallel to the hull
    and was done; and the largest change of a piece's pose in one step, turning, sliding or
    done (m: of its centre's depth plus half its length times its tilt)."""
    cfg = exercise_config(tmp_path_factory.mktemp(name) / "tiles", 400.0, 600.0, 50.0, start_north=-60.0)
    model = build_world(cfg, None)
    if at_once:
        model = dataclasses.replace(model, ships=(dataclasses.replace(model.ship, bow_surface=(0.0, 1.0)),))
    data = start_world(model, cfg)
    seen, done, jump, pose = [], {}, 0.0, {}
    for _ in range(STEPS):
        before = float(data.ship.eta[0])  # north, m: the ship heads north
        step(model, data, DT)
        st = data.ice.state
        under = np.flatnonzero((st.turn > 0.0) & st.submerged & (st.status == FloeStatus.FREE))
        length = np.sqrt(model.ice.plan_area[st.gcell[under]])
        turning = under[st.turn[under] > length]
        g = st.gcell[turning]
        seen.append((turning, np.hypot(st.roll[turning], st.pitch[turning]),
                     model.ice.z_equilibrium[g] - st.heave[turning], np.sqrt(model.ice.plan_area[g])))
        for row in under.tolist():
            done.setdefault(row, [None, before, None, None])
        for row, d in zip(under.tolist(), length.tolist()):
            if done[row][2] is None and st.turn[row] <= d:
                done[row][2] = float(data.ship.eta[0])
        for row in [r for r in done if done[r][0] is None and st.turn[r] == 0.0 and st.submerged[r]]:
            done[row][0], done[row][3] = float(st.roll[row]), float(data.ship.eta[0])
        for row in list(pose):
            if st.submerged[row]:
                was, d = pose[row], float(np.sqrt(model.ice.plan_area[st.gcell[row]]))
                jump = max(jump, abs(st.heave[row] - was[0]) + 0.5 * d * abs(np.hypot(st.roll[row], st.pitch[row])
                                                                              - was[1]))
        pose = {r: (float(st.heave[r]), float(np.hypot(st.roll[r], st.pitch[r]))) for r in under.tolist()}
    return model, data, seen, done, jump


@pytest.fixture(scope="module")
def turned(tmp_path_factory):
    return _run(tmp_path_factory, "turning")


def test_struck_pieces_turn_towards_the_hulls_surface_angle(turned):
    model, _, seen, done, _ = turned
    psi = bow_normal_angle(model.ship.stem_angle, model.ship.waterline_angle)
    rows = np.unique(np.concatenate([s[0] for s in seen]))
    tilt = np.concatenate([s[1] for s in seen])
    depth = np.concatenate([s[2] for s in seen])
    length = np.concatenate([s[3] for s in seen])
    assert len(rows) > 20  # the bow turns pieces as it breaks them
    assert tilt.max() <= psi + 1e-5 and tilt.max() > 0.8 * psi  # up to parallel with the hull, no farther
    assert (tilt > 0.3 * psi).mean() > 0.3  # seen turned, not only starting
    # the far edge stays at the waterline: the centre is half the length's rise below its draft
    assert depth == pytest.approx(0.5 * length * np.sin(tilt), abs=2e-3)
    finished = [roll for roll, *_ in done.values() if roll is not None]
    assert len(finished) > 10 and finished == pytest.approx([PUSHED_DOWN_TILT] * len(finished))


def test_a_piece_turns_over_its_length_of_the_surfaces_advance(turned):
    """The hull's surface at the bow crosses the waterline by sin(alpha) of the ship's
    advance, so a piece lies parallel to it after the ship has advanced d / sin(alpha)."""
    model, data, _, done, _ = turned
    rows = [r for r, (roll, *_) in done.items() if roll is not None]
    length = np.sqrt(model.ice.plan_area[data.ice.state.gcell[rows]])
    advance = np.array([done[r][2] - done[r][1] for r in rows])
    expected = length / math.sin(model.ship.waterline_angle)
    step_advance = 4.0 * DT  # m: a step's advance at most (the ship makes under 4 m/s)
    assert np.all(advance >= expected - 1e-6)  # never done sooner
    assert np.mean(advance <= expected + step_advance) > 0.95  # done within the step it is due
    assert np.median(advance / expected) == pytest.approx(1.0, abs=0.02)
    assert np.all(advance > 1.5 * length)  # not the ship's own advance (the default ship: alpha 30 deg)


def test_the_piece_slides_under_over_another_length_without_a_jump(turned):
    """Lying parallel to the hull, a piece slides under it to the submerged pose over
    another length of the surface's advance; no step moves a piece's pose by more than a
    few centimetres (it jumped by up to 0.84 m when it took the submerged pose at once)."""
    model, data, _, done, jump = turned
    rows = [r for r, (roll, *_) in done.items() if roll is not None]
    length = np.sqrt(model.ice.plan_area[data.ice.state.gcell[rows]])
    slide = np.array([done[r][3] - done[r][2] for r in rows])
    expected = length / math.sin(model.ship.waterline_angle)
    assert np.median(slide / expected) == pytest.approx(1.0, abs=0.02)
    assert jump < 0.1


def test_the_turn_changes_no_planar_physics(turned, tmp_path_factory):
    _, data, _, _, _ = turned
    _, at_once, seen, _, _ = _run(tmp_path_factory, "at-once", at_once=True)
    assert not any(len(s[0]) for s in seen)
    a, b = data.ice.state, at_once.ice.state
    assert a.n == b.n and np.array_equal(a.status, b.status) and np.array_equal(a.xy, b.xy)
    assert np.array_equal(data.ship.eta, at_once.ship.eta)
