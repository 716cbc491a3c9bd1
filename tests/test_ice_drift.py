"""Free drift of the broken ice in the wind (issue 26, item 3 in part): Nansen's rule
(``sim_core.ice.drift``), about 2 % of the wind's speed, turned 30 degrees to the right of
the wind in the northern hemisphere and to the left in the southern; in the world, the
floes drifting free take the current plus that drift."""
import math

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.node.world_setup import build_world, start_world
from sim_core.ice.drift import free_drift
from sim_core.ice.floes import FloeStatus
from sim_core.instructor import SetEnvironment
from sim_core.world import Controls, step

DT = 1.0 / 30.0
LAT = math.radians(74.0)


def _bearing(north: float, east: float) -> float:
    return math.degrees(math.atan2(east, north)) % 360.0


def test_the_ice_drifts_at_two_percent_of_the_wind_turned_to_the_right_in_the_north():
    north, east = free_drift(10.0, 0.0, LAT)  # a wind blowing to the north
    assert math.hypot(north, east) == pytest.approx(0.2)
    assert _bearing(north, east) == pytest.approx(30.0)
    north, east = free_drift(0.0, -10.0, LAT)  # to the west: the drift turns to the north-west
    assert _bearing(north, east) == pytest.approx(300.0)


def test_in_the_south_it_turns_to_the_left_and_on_the_equator_not_at_all():
    assert _bearing(*free_drift(10.0, 0.0, -LAT)) == pytest.approx(330.0)
    assert _bearing(*free_drift(10.0, 0.0, 0.0)) == pytest.approx(0.0)
    assert free_drift(0.0, 0.0, LAT) == (0.0, 0.0)


def test_a_wind_sets_the_broken_floes_drifting_downwind_turned_right(tmp_path):
    cfg = exercise_config(tmp_path / "tiles", 800.0, 800.0, start_north=-60.0)  # origin 74 N
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    for _ in range(600):  # 20 s into the ice: floes broken
        step(model, data, DT)
    for _ in range(600):  # the ship stopped
        step(model, data, DT, Controls(telegraph="stop"))
    # 15 m/s from the north: the ice drifts at 0.3 m/s to 210 degrees (south-south-west)
    step(model, data, DT, commands=(SetEnvironment((("wind_speed", 15.0), ("wind_from", 0.0))),))
    for _ in range(1800):  # 60 s: three of the floes' 20 s drag time
        step(model, data, DT)
    st = data.ice.state
    free = data.live_rows[st.status[data.live_rows] == FloeStatus.FREE]
    out = free[st.xy[free, 1] < 0.0]  # out of the ice, south of its edge: drifting free
    assert len(out) > 20 and not st.resting[out].any()  # drifting free: none at rest
    reached = 0.3 * (1.0 - math.exp(-3.0))  # linear drag towards the drift velocity
    assert np.median(st.vel[out, 1]) == pytest.approx(-reached * math.cos(math.radians(30.0)), abs=0.02)
    assert np.median(st.vel[out, 0]) == pytest.approx(-reached * math.sin(math.radians(30.0)), abs=0.02)
