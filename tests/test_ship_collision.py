"""Own ships collide instead of passing through one another (issue 31): the impact of
Pedersen and Zhang (1998) between two hulls with their added masses, the push-out of
overlapping ships, a replayed ship that gives way to nothing, and the alarm on both
bridges. The ships lie in open water south of a small ice field."""
import math
import re

import numpy as np
import pytest

from conftest import exercise_config
from bridge_node.exercise.collision_alarms import CLEAR_S, COLLISION_ALARM, VESSEL_COLLISION_ALARM, CollisionAlarms
from bridge_node.control.status import exercise_status
from bridge_node.exercise.fleet import Bridge
from bridge_node.exercise.tick import TickOutcome
from bridge_node.links.hub import LinkHub
from bridge_node.links.settings import ArbitrationSettings
from bridge_node.node.bridges import bridges_summary
from bridge_node.node.world_setup import build_world
from sim_core.frames.hull_contour import waterline_contour
from sim_core.frames.ship_frame import ship_to_world, ship_vector_to_world, world_vector_to_ship
from sim_core.ship.collision import MAX_PUSH_OUT, SLOP, ship_collisions, waterline_overlap
from sim_core.instructor import AddVessel, OtherVessel
from sim_core.world import Controls, KinematicPose, ShipStart, compile_world, new_world_data, step

DT = 1.0 / 60.0
NORTH = -600.0  # m: open water, south of the field
SPEED = 3.0  # m/s: the striker's


@pytest.fixture(scope="module")
def two_ships(tmp_path_factory):
    """A world of two of the default ship."""
    cfg = exercise_config(tmp_path_factory.getbasetemp() / "collision", 200.0, 300.0, 100.0, start_north=-100.0)
    base = build_world(cfg, None)
    return compile_world(base.ship, base.ice, base.scene, base.origin, (), base.rubble, others=(base.ship,))


def _overlap(model, data) -> float:
    """How far the two waterlines overlap now, m (0 apart)."""
    found = waterline_overlap(*(ship_to_world(model.contours[k], *data.ships[k].eta[[0, 1, 5]]) for k in range(2)))
    return 0.0 if found is None else found[2]


def _ram(model):
    """Ship 0 heading east at SPEED, its stem 5 m from the side of ship 1, stopped heading
    north, aimed at its midship."""
    p = model.ship.particulars
    return new_world_data(model, NORTH, -0.5 * (p.length + p.beam) - 5.0, 0.5 * math.pi, SPEED,
                          others=(ShipStart(NORTH, 0.0, 0.0, 0.0),))


def test_a_ship_rammed_amidships_is_pushed_aside_not_through(two_ships):
    model = two_ships
    data = _ram(model)
    first, deepest = None, 0.0
    for _ in range(int(20.0 / DT)):
        events = step(model, data, DT, [Controls(), Controls()])
        first = first or (events.collisions[0] if events.collisions else None)
        deepest = max(deepest, _overlap(model, data))
    assert first is not None and first.ships == (0, 1)
    assert first.closing_speed == pytest.approx(SPEED, rel=0.05)
    assert first.normal[1] == pytest.approx(1.0, abs=0.01)  # east, from the striker into the struck ship
    assert deepest < 0.2  # m: without the impact the stem would have run the beam's 24 m through
    striker, struck = data.ships
    assert struck.eta[1] > 5.0 and struck.nu[1] > 0.3  # pushed east: sideways, to its starboard
    assert striker.nu[0] < 0.5 * SPEED
    # Pedersen and Zhang's perpendicular impact at the struck ship's midship, sticking and
    # plastic: E = v^2 / 2 / (1 / m_a + 1 / m_b), with the striker's surge mass m_a and the
    # struck ship's sway mass at the point, its yaw coupling taken in: 1 / m_b = (M^-1)_vv
    # of its sway-yaw matrix about midship (the point's offset along the ship is x).
    x = world_vector_to_ship((first.east - 0.0, first.north - NORTH), 0.0)[0]
    arm = np.array([1.0, x])
    inv_struck = arm @ model.ship.inv_sway_yaw @ arm
    expected = 0.5 * SPEED**2 / (1.0 / model.ship.surge_mass + inv_struck)
    assert first.energy == pytest.approx(expected, rel=0.05)


def test_the_impact_loads_are_equal_and_opposite(two_ships):
    """At the first contact the two ships' loads are one impulse, each way: the forces sum to
    nothing in the world, and so do their moments about one point."""
    model = two_ships
    data = _ram(model)
    while _overlap(model, data) == 0.0:
        step(model, data, DT, [Controls(), Controls()])
    loads, contacts = ship_collisions(model.ships, data.ships, model.contours, [False, False], DT)
    assert len(contacts) == 1 and contacts[0].impulse > 0.0
    forces = [np.array(ship_vector_to_world(tuple(load[:2]), ship.eta[5])) for load, ship in zip(loads, data.ships)]
    assert np.linalg.norm(forces[0] + forces[1]) < 1e-6 * np.linalg.norm(forces[0])
    # each load's moment about the origin: its midship's arm across its force, less its own moment (+ to starboard)
    moments = [ship.eta[1] * f[1] - ship.eta[0] * f[0] - load[2] for ship, f, load in zip(data.ships, forces, loads)]
    assert abs(moments[0] + moments[1]) < 1e-6 * abs(moments[0]) + 1.0


def test_a_replayed_ship_follows_its_log_and_the_other_gives_way(two_ships):
    model = two_ships
    data = _ram(model)
    east = data.ships[0].eta[1]
    for _ in range(int(15.0 / DT)):
        east += 2.0 * DT
        events = step(model, data, DT, [Controls(kinematic=KinematicPose(NORTH, east, 0.5 * math.pi, 2.0)), Controls()])
        assert data.ships[0].eta[1] == east  # the log rules
    assert events.collisions and _overlap(model, data) < 0.5
    assert data.ships[1].eta[1] > 15.0  # shoved east ahead of the stem


def test_ships_placed_into_each_other_are_parted_gently(two_ships):
    """Two ships side by side, stopped, their beams 3 m into each other (as an instructor's
    move can leave them): the push-out parts them, no faster than its cap."""
    model = two_ships
    beam = model.ship.particulars.beam
    data = new_world_data(model, NORTH, 0.0, 0.0, 0.0, others=(ShipStart(NORTH, beam - 3.0, 0.0, 0.0),))
    assert _overlap(model, data) == pytest.approx(3.0, abs=0.05)
    fastest = 0.0
    for _ in range(int(30.0 / DT)):
        step(model, data, DT, [Controls(), Controls()])
        fastest = max(fastest, data.ships[1].nu[1] - data.ships[0].nu[1])
    assert _overlap(model, data) < SLOP + 0.05
    assert fastest < 1.2 * MAX_PUSH_OUT


def _outcome(events, now: float) -> TickOutcome:
    return TickOutcome(events, Controls(), (), now, None)


def test_both_bridges_hear_the_collision_alarm_until_the_ships_are_apart(two_ships):
    """The striker rams at 5.8 kn with its engine ordered full astern: the alarm on both
    bridges names the other ship with the closing speed and the energy, and clears once they
    have been apart for CLEAR_S. (Measured: the struck ship, shoved at 1.7 s, drew away;
    the striker, its engine still waiting to reverse, caught up with it at 0.36 kn at 20 s
    and pushed it sideways until 56 s: a second alarm, cleared at 61 s.)"""
    model = two_ships
    data = _ram(model)
    bridges = [Bridge(LinkHub([], ArbitrationSettings()), 230_000_001 + k, name)
               for k, name in enumerate(("ODEN", "ATLE"))]
    alarms = CollisionAlarms([b.hub for b in bridges], [b.name for b in bridges])
    now, seen = 0.0, None
    for _ in range(int(80.0 / DT)):
        now += DT
        events = step(model, data, DT, [Controls(telegraph="full_astern"), Controls()])
        alarms.on_step(_outcome(events, now))
        if events.collisions:
            last = now
        if COLLISION_ALARM in bridges[1].hub.active_alarms and not seen:  # the instructor's status: every bridge's
            seen = exercise_status(events, None, bridges[0].hub, [("ATLE", bridges[1].hub)])["alarms"]
    first = [next(a for _, a in h.hub.alarm_log if a.active) for h in bridges]
    assert [(a.number, a.text) for a in first] == [(COLLISION_ALARM + 1, "collision with ATLE 5.8 kn 78 MJ"),
                                                   (COLLISION_ALARM, "collision with ODEN 5.8 kn 78 MJ")]
    raised = [t for t, a in bridges[0].hub.alarm_log if a.active]
    cleared = [t for t, a in bridges[0].hub.alarm_log if not a.active and a.text == "clear of ATLE"]
    assert len(raised) == len(cleared) == len(alarms.log)  # each raised once per collision, then cleared
    assert all(c >= r + CLEAR_S for r, c in zip(raised, cleared)) and cleared[-1] >= last + CLEAR_S
    assert not bridges[0].hub.active_alarms and not bridges[1].hub.active_alarms
    assert [a["text"] for a in seen] == [first[0].text, "ATLE: " + first[1].text]
    summary = bridges_summary(bridges[0].hub, bridges)  # the run's summary: each collision once
    assert len(summary["collisions"]) == 2 and summary["collisions"][0] == first[0].text
    again = re.fullmatch(r"collision with ATLE (\d+\.\d) kn 0 MJ", summary["collisions"][1])
    assert again and 0.2 <= float(again[1]) <= 0.5  # slowly: 0.365 kn, printed 0.3 with earlier package versions
    assert summary["alarms"] == []


def test_a_ship_that_rams_the_instructors_vessel_stops_against_it(two_ships):
    """A vessel the instructor steers follows its script whatever it meets: the own ship
    that rams it amidships stops against it, with the energy of an impact against a body
    that does not give way (the striker's surge mass alone), and its bridge gets alarm
    VESSEL_COLLISION_ALARM naming the vessel."""
    one = compile_world(two_ships.ship, two_ships.ice, two_ships.scene, two_ships.origin, (), two_ships.rubble)
    p = one.ship.particulars
    data = new_world_data(one, NORTH, -0.5 * (p.length + 20.0) - 5.0, 0.5 * math.pi, SPEED)
    add = AddVessel(230_000_009, OtherVessel("ODEN", NORTH, 0.0, 0.0, 0.0, 100.0, 20.0))
    hub = LinkHub([], ArbitrationSettings())
    alarms = CollisionAlarms([hub], [""])
    first, deepest, now = None, 0.0, 0.0
    for k in range(int(20.0 / DT)):
        now += DT
        events = step(one, data, DT, Controls(telegraph="stop" if k else None), (add,) if k == 0 else ())
        alarms.on_step(_outcome(events, now))
        first = first or (events.collisions[0] if events.collisions else None)
        vessel = ship_to_world(waterline_contour(100.0, 20.0), NORTH, 0.0, 0.0)
        found = waterline_overlap(ship_to_world(one.contour, *data.ship.eta[[0, 1, 5]]), vessel)
        deepest = max(deepest, 0.0 if found is None else found[2])
    assert first is not None and first.ships == (0,) and first.vessel == 230_000_009
    assert first.closing_speed == pytest.approx(SPEED, rel=0.05)
    assert first.energy == pytest.approx(0.5 * SPEED**2 * one.ship.surge_mass, rel=0.05)
    assert deepest < 0.2 and data.ship.nu[0] < 0.3  # stopped against it, not through its 20 m beam
    assert (data.vessels[230_000_009].north, data.vessels[230_000_009].east) == (NORTH, 0.0)  # unmoved
    raised = next(a for _, a in hub.alarm_log if a.active)
    assert raised.number == VESSEL_COLLISION_ALARM and raised.text.startswith("collision with ODEN 5.8 kn")
    assert bridges_summary(hub, [])["collisions"] == [raised.text]
