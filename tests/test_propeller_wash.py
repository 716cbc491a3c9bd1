"""The propeller's jet churns the broken ice astern (issue 28, item 2): momentum theory's
slipstream speed, Albertson's spreading jet, and in the world the floes in the channel
astern pushed aft by it, and left at rest without it."""
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.node.world_setup import build_world, start_world
from sim_core.ice.floes import FloeStatus
from sim_core.ship.propeller_jet import ESTABLISHED, SPREAD, jet_velocity, propeller_jet, slipstream_speed
from sim_core.world import Controls, step

RHO = 1025.0
DT = 1.0 / 30.0


def test_the_bollard_slipstream_is_blaauw_and_van_de_kaas_efflux_speed():
    n, d, kt = 2.0, 5.6, 0.29  # rev/s, m
    thrust = RHO * n * n * d**4 * kt
    assert slipstream_speed(thrust, 0.0, d, RHO) == pytest.approx(math.sqrt(8.0 / math.pi) * n * d * math.sqrt(kt))
    assert math.sqrt(8.0 / math.pi) == pytest.approx(1.6, abs=0.005)  # their 1.6 n D sqrt(K_T)
    under_way = slipstream_speed(thrust, 3.0, d, RHO)
    assert 0.0 < under_way < slipstream_speed(thrust, 0.0, d, RHO)  # the same thrust adds less to a faster inflow


def test_the_jet_flows_astern_spreads_and_slows_as_albertsons():
    jet = propeller_jet(np.zeros(2), np.array([0.0, 1.0]), 8.0e5, 0.0, 5.6, 9.0, RHO)  # heading north
    d0 = 5.6 / math.sqrt(2.0)
    assert jet.diameter == pytest.approx(d0) and jet.depth == pytest.approx(9.0 - 0.55 * 5.6)
    on_axis = propeller_jet(np.zeros(2), np.array([0.0, 1.0]), 8.0e5, 0.0, 5.6, 0.55 * 5.6, RHO)  # axis at the surface
    x = np.array([2.0, ESTABLISHED * d0, 2.0 * ESTABLISHED * d0, 4.0 * ESTABLISHED * d0])
    v = jet_velocity(on_axis, np.column_stack([np.zeros(4), -x]))
    assert np.all(v[:, 0] == 0.0) and np.all(v[:, 1] < 0.0)  # astern
    assert -v[:, 1] == pytest.approx(on_axis.speed * np.array([1.0, 1.0, 0.5, 0.25]))
    across = SPREAD * x[2]  # one standard deviation off the axis
    side = jet_velocity(on_axis, np.array([[across, -x[2]]]))
    assert -side[0, 1] == pytest.approx(0.5 * on_axis.speed * math.exp(-0.5))
    ahead = jet_velocity(jet, np.array([[0.0, 10.0], [0.0, -1.0e4]]))
    assert np.all(ahead == 0.0)  # none ahead of the propeller, none beyond its reach
    astern = propeller_jet(np.zeros(2), np.array([0.0, 1.0]), -8.0e5, -1.0, 5.6, 0.55 * 5.6, RHO)
    assert jet_velocity(astern, np.array([[0.0, 50.0]]))[0, 1] > 0.0  # going astern the jet flows forward
    assert propeller_jet(np.zeros(2), np.array([0.0, 1.0]), 0.0, 0.0, 5.6, 9.0, RHO) is None


def _floes_astern(wash: bool, cache: Path) -> tuple[np.ndarray, float]:
    """Velocities (m/s, east, north) of the floes above water in the channel 50-150 m
    astern of the ship after 120 s at full ahead into 0.5 m level ice, heading north; and
    the most the jet gives."""
    cfg = exercise_config(cache, 800.0, 800.0, start_north=-60.0)
    cfg = cfg.model_copy(update={"ice_dynamics": cfg.ice_dynamics.model_copy(update={"propeller_wash": wash})})
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    for _ in range(3600):
        step(model, data, DT, Controls(telegraph="full_ahead"))
    st = data.ice.state
    free = data.live_rows[(st.status[data.live_rows] == FloeStatus.FREE) & ~st.submerged[data.live_rows]]
    stern = data.ship.eta[0] - 0.5 * model.ship.L
    behind = stern - st.xy[free, 1]
    rows = free[(behind > 50.0) & (behind < 150.0) & (np.abs(st.xy[free, 0] - data.ship.eta[1]) < 15.0)]
    m = model.ship
    thrust = m.rho * data.ship.rps**2 * m.d_p**4 * m.particulars.propeller.k0  # at most: K_T at J = 0
    most = slipstream_speed(thrust, 0.0, m.d_p, m.rho)
    return st.vel[rows], most


def test_the_wash_pushes_the_broken_ice_astern_along_the_channel(tmp_path_factory):
    cache = tmp_path_factory.mktemp("tiles")
    washed, most = _floes_astern(True, cache)
    still, _ = _floes_astern(False, cache)
    assert len(washed) > 100 and len(still) > 100
    assert np.median(still[:, 1]) == pytest.approx(0.0, abs=0.02)  # without the jet: at rest in the channel
    assert np.median(washed[:, 1]) < -0.1  # pushed aft (south)
    assert np.abs(np.median(washed[:, 0])) < 0.1  # along the channel, not across it
    assert np.hypot(*washed.T).max() < most  # never faster than the water the jet leaves the propeller with
