"""The instructor's commands: checked whole (a bad one names its field, value and range and
changes nothing), and what each does to the world at the step that applies it."""
import math

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.control.commands import CommandError, command_from_record, command_record, parse_command
from bridge_node.control.queue import CommandQueue
from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, open_water_world, start_world
from sim_core.frames.units import KNOT
from sim_core.ice.floes import FloeStatus
from sim_core.instructor import (
    EngineFailure,
    Freeze,
    Reposition,
    SetClock,
    SetEnvironment,
    SteeringFailure,
)
from sim_core.world import Controls, step

DT = 1.0 / 30.0


@pytest.mark.parametrize("message, words", [
    ({"command": "teleport"}, ["'teleport'", "unknown", "allowed: freeze"]),
    ({"command": "wind", "speed_kn": "gale", "from_deg": 90.0}, ["speed_kn", '"gale"', "valid number"]),
    ({"command": "wind", "speed_kn": 150.0, "from_deg": 90.0}, ["speed_kn = 150.0", "less than or equal to 100"]),
    ({"command": "visibility", "visibility_m": float("nan")}, ["visibility_m = NaN", "finite"]),
    ({"command": "visibility", "visibility_m": 10.0}, ["visibility_m = 10.0", "greater than or equal to 50"]),
    ({"command": "current", "speed_kn": 1.0, "to_deg": 360.0}, ["to_deg = 360.0", "less than 360"]),
    ({"command": "steering_failure", "pumps_failed": 3}, ["pumps_failed = 3", "less than or equal to 2"]),
    ({"command": "steering_failure", "pumps_failed": True}, ["pumps_failed = true"]),
    ({"command": "reposition", "heading_deg": 10.0}, ["latitude_deg and longitude_deg, or north_m and east_m"]),
    ({"command": "reposition", "north_m": 1.0, "east_m": 1.0, "latitude_deg": 74.0, "heading_deg": 0.0},
     ["latitude_deg and longitude_deg, or north_m and east_m"]),
    ({"command": "clock", "time_of_day": "25:00"}, ["time_of_day", "hour value is outside"]),
    ({"command": "freeze", "at": 3}, ["at = 3", "Extra inputs"]),
    ([1, 2], ["unknown"]),
])
def test_a_bad_command_is_refused_whole_naming_field_value_and_range(message, words):
    with pytest.raises(CommandError) as refused:
        parse_command(message)
    for word in words:
        assert word in str(refused.value), str(refused.value)


def test_commands_become_world_commands_in_si_and_records_round_trip():
    model, data = open_water_world(load_config(), None)
    queue = CommandQueue(capacity=3, per_tick=2)
    for message in ({"command": "wind", "speed_kn": 20.0, "from_deg": 90.0},
                    {"command": "reposition", "latitude_deg": 74.01, "longitude_deg": 20.0, "heading_deg": 45.0,
                     "speed_kn": 4.0},
                    {"command": "clock", "time_of_day": "23:30"}):
        assert queue.put(parse_command(message))
    assert not queue.put(parse_command({"command": "freeze"}))  # full: refused, nothing dropped silently
    wind, move = queue.take(model, data)  # two a tick
    assert wind == SetEnvironment((("wind_speed", 20.0 * KNOT), ("wind_from", math.pi / 2)))
    assert move.north == pytest.approx(1114.0, abs=10.0) and move.east == pytest.approx(0.0, abs=1e-6)
    assert move.heading == pytest.approx(math.pi / 4) and move.speed == pytest.approx(4.0 * KNOT)
    clock, = queue.take(model, data)
    assert (clock.utc - data.epoch) % 86400.0 == pytest.approx((23.5 * 3600.0 - data.epoch % 86400.0) % 86400.0)
    assert queue.take(model, data) == ()
    for command in (wind, move, clock, Freeze(True), SteeringFailure(0), EngineFailure(0.25)):
        assert command_from_record(command_record(command)) == command


def test_freeze_takes_orders_moves_nothing_and_stops_the_clock():
    model, data = open_water_world(load_config(), None)
    data.ship.nu[0] = 5.0
    step(model, data, DT)
    frozen = step(model, data, DT, Controls(rudder=0.3), (Freeze(True),))
    north, t = data.ship.eta[0], data.time
    held = [step(model, data, DT) for _ in range(30)]
    assert frozen.commands == (Freeze(True),) and frozen.environment.frozen
    assert data.time == t and data.ship.eta[0] == north and data.ship.rudder == 0.0  # nothing moved
    assert [e.seq for e in held] == list(range(frozen.seq + 1, frozen.seq + 31))  # every tick still publishes
    assert data.ship.rudder_order == pytest.approx(0.3)  # the order taken, obeyed after the resume
    step(model, data, DT, commands=(Freeze(False),))
    assert data.time > t and data.ship.eta[0] > north and data.ship.rudder > 0.0


def test_steering_pumps_and_engine_power():
    model, data = open_water_world(load_config(), None)
    rate = model.ship.rudder_rate
    moved = []
    for pumps in (2, 1, 0):
        step(model, data, DT, Controls(rudder=0.0), (SteeringFailure(2),))
        for _ in range(60):  # back to midships at the full rate
            step(model, data, DT)
        step(model, data, DT, Controls(rudder=math.radians(30.0)), (SteeringFailure(pumps),))
        for _ in range(29):
            step(model, data, DT)
        moved.append(data.ship.rudder)
    assert moved[0] == pytest.approx(rate * 1.0, rel=1e-6)  # 30 steps of 1/30 s: 1 s at the full rate
    assert moved[1] == pytest.approx(rate * 0.5, rel=1e-6) and moved[2] == 0.0  # half; stuck
    step(model, data, DT, Controls(telegraph="navigation_full_ahead"), (EngineFailure(0.125),))
    for _ in range(2700):  # 90 s: the shaft's 8 s lag has settled
        step(model, data, DT)
    assert data.ship.rps == pytest.approx(0.5 * model.ship.rps_ahead_max, rel=1e-3)  # the cube root of 1/8
    step(model, data, DT, commands=(EngineFailure(0.0),))
    for _ in range(1800):
        step(model, data, DT)
    assert 0.0 <= data.ship.rps < 1e-3  # blackout: the shaft has run down (0.06 rpm after 60 s)


def test_a_beam_wind_sets_the_ship_to_leeward_and_a_current_carries_it():
    model, data = open_water_world(load_config(), None)
    step(model, data, DT, commands=(SetEnvironment((("wind_speed", 20.0), ("wind_from", math.pi / 2))),))
    for _ in range(1800):  # 60 s
        step(model, data, DT)
    assert data.ship.eta[1] < -1.0  # a wind from the east pushes the ship west
    assert abs(data.ship.eta[0]) < abs(data.ship.eta[1])
    model, data = open_water_world(load_config(), None)
    step(model, data, DT, commands=(SetEnvironment((("current_speed", 1.0), ("current_to", math.pi))),))
    for _ in range(299):
        step(model, data, DT)
    assert data.ship.eta[0] == pytest.approx(-10.0, abs=1e-6) and abs(data.ship.eta[1]) < 1e-6  # 10 s at 1 m/s south
    events = step(model, data, DT)
    assert events.ship.speed_over_ground == pytest.approx(1.0) and events.ship.speed_longitudinal == 0.0


@pytest.fixture(scope="module")
def ice(tmp_path_factory):
    cfg = exercise_config(tmp_path_factory.mktemp("cmd") / "tiles", 800.0, 800.0, start_north=-60.0)
    return cfg, build_world(cfg, None)


def test_a_current_sets_the_broken_floes_drifting_with_the_water(tmp_path):
    cfg = exercise_config(tmp_path / "tiles", 800.0, 800.0, start_north=-60.0)
    cfg = cfg.model_copy(update={"ice_dynamics": cfg.ice_dynamics.model_copy(update={"rest_distance": 80.0})})
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    for _ in range(600):  # 20 s into the ice: floes broken
        step(model, data, DT)
    for _ in range(1800):  # the ship stopped: 60 s for the floes far from it to come to rest
        step(model, data, DT, Controls(telegraph="stop"))
    rested = np.flatnonzero(data.ice.state.resting)
    assert len(rested)
    step(model, data, DT, commands=(SetEnvironment((("current_speed", 0.5), ("current_to", math.pi))),))
    woken = np.zeros(len(rested), bool)
    for _ in range(1800):  # 60 s: three of the floes' 20 s drag time
        step(model, data, DT)
        woken |= ~data.ice.state.resting[rested]
    st = data.ice.state
    free = data.live_rows[st.status[data.live_rows] == FloeStatus.FREE]
    assert woken.all()  # those at rest when the current set in were woken to feel it
    out = free[st.xy[free, 1] < 0.0]  # out of the ice, south of its edge: drifting free
    assert len(out) > 20 and not st.resting[out].any()  # drifting free, none comes to rest again
    # linear drag towards the water's velocity: 0.5 m/s south, reached to 1 - exp(-60 / 20)
    assert np.median(st.vel[out, 1]) == pytest.approx(-0.5 * (1.0 - math.exp(-3.0)), abs=0.01)
    assert abs(np.median(st.vel[out, 0])) < 0.01
    assert np.median(st.vel[free, 1]) < -0.3  # those in the channel too, rubbing its walls


def test_a_reposition_waits_for_its_tiles_then_moves_and_is_published_as_applied(ice):
    cfg, model = ice
    data = start_world(model, cfg)
    step(model, data, DT)
    to = Reposition(600.0, 600.0, math.pi / 2, 3.0)
    first = step(model, data, DT, commands=(to,))
    steps = [first]
    while not steps[-1].commands and len(steps) < 3000:
        steps.append(step(model, data, DT))
    moved = steps[-1]
    assert first.commands == () and len(steps) > 1  # the tiles were prepared over several steps first
    assert moved.commands == (Reposition(600.0, 600.0, math.pi / 2, 3.0, at_once=True),)
    assert (moved.ship.north, moved.ship.east) == pytest.approx((600.0, 600.0 + 3.0 * DT), abs=0.05)
    assert data.late_switches == 0  # every tile around the new place was ready at the switch


def test_the_clock_command_moves_the_exercise_clock():
    model, data = open_water_world(load_config(), None)
    step(model, data, DT)
    events = step(model, data, DT, commands=(SetClock(1_800_000_000.0),))
    assert events.ship.utc == pytest.approx(1_800_000_000.0 + DT)


def test_other_vessels_are_added_steered_moved_and_removed_in_the_world():
    model, data = open_water_world(load_config(), None)
    queue = CommandQueue()
    for message in ({"command": "add_vessel", "mmsi": 230000001, "name": "ODEN", "length_m": 108.0, "beam_m": 31.0,
                     "north_m": 500.0, "east_m": 0.0, "course_deg": 90.0, "speed_kn": 10.0},
                    {"command": "steer_vessel", "mmsi": 230000009, "course_deg": 0.0, "speed_kn": 1.0}):
        queue.put(parse_command(message))
    added = step(model, data, 1.0, commands=queue.take(model, data))
    assert [type(c).__name__ for c in added.commands] == ["AddVessel"]  # the unknown MMSI: nothing applied
    (mmsi, oden), = added.vessels
    assert mmsi == 230000001 and oden.name == "ODEN" and oden.east == pytest.approx(10.0 * KNOT)  # one second on
    for message in ({"command": "steer_vessel", "mmsi": 230000001, "course_deg": 180.0, "speed_kn": 2.0},):
        queue.put(parse_command(message))
    step(model, data, 10.0, commands=queue.take(model, data))
    assert data.vessels[230000001].north == pytest.approx(500.0 - 20.0 * KNOT)
    queue.put(parse_command({"command": "move_vessel", "mmsi": 230000001, "latitude_deg": 74.0,
                             "longitude_deg": 20.0}))
    moved = step(model, data, DT, commands=queue.take(model, data))
    assert moved.vessels[0][1].north == pytest.approx(-2.0 * KNOT * DT, abs=1e-9)  # at the origin, then on
    assert command_from_record(command_record(added.commands[0])) == added.commands[0]
    queue.put(parse_command({"command": "remove_vessel", "mmsi": 230000001}))
    assert step(model, data, DT, commands=queue.take(model, data)).vessels == ()
    with pytest.raises(CommandError, match="name"):
        parse_command({"command": "add_vessel", "mmsi": 230000001, "name": "od{en}", "length_m": 10.0,
                       "beam_m": 3.0, "north_m": 0.0, "east_m": 0.0, "course_deg": 0.0})


@pytest.mark.parametrize("record", [
    {"type": "SetEnvironment", "changes": [["visibility", float("nan")]]},
    {"type": "SetEnvironment", "changes": [["frozen", 1.0]]},
    {"type": "Reposition", "north": 1.0, "east": 2.0, "heading": 0.1, "speed": float("inf"), "at_once": True},
    {"type": "Sink"}, {"type": "Freeze"}, ["Freeze"],
])
def test_a_command_record_that_is_no_command_is_refused(record):
    """commands.log is read back by a replay: a line changed by hand or torn cannot put a
    NaN or an unknown field into the world."""
    with pytest.raises(CommandError, match="not a command record"):
        command_from_record(record)
