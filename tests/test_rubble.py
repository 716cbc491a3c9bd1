"""Brash and ridges (issue 26, item 2): ice the world does not lay out as bodies meets the
hull through published models. A brash channel resists by the Finnish-Swedish rules'
channel formula (Riska et al. 1997), a ridge keel by Dolgopolov et al. (1975); the tests
check the formulas against hand calculations and the load on the hull in the running world
against the models."""
import math

import numpy as np
import pytest
import shapely
from conftest import exercise_config
from pydantic import ValidationError

from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet
from bridge_node.render.classes import CLASS_INDEX, class_of_pixels
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.stream.world_view import WorldView
from sim_core.regimes.ridge_settings import RidgeFieldSettings
from sim_core.regimes.rubble import RidgeField, compile_rubble, keel_depth_at, rubble_at
from sim_core.regimes.settings import RegionSettings
from sim_core.ship.rubble_resistance import (
    FSICR_SPEED,
    BowForm,
    brash_channel_resistance,
    channel_speed_factor,
    keel_resistance,
)
from sim_core.world import snapshot, step

RIDGE_LINE = 500.0  # m north: the test field's ridge line
RIDGES = {"name": "ridges", "polygon_m": [[0.0, 300.0], [400.0, 300.0], [400.0, 900.0], [0.0, 900.0]],
          "direction_deg": 90.0, "spacing_m": 300.0, "through_m": [0.0, RIDGE_LINE], "width_m": 20.0,
          "keel_depth_m": 4.5}
CHANNEL = {"name": "old channel", "polygon_m": [[100.0, 0.0], [200.0, 0.0], [200.0, 900.0], [100.0, 900.0]],
           "concentration": 9, "ice": [{"stage": "medium_first_year", "floe_size": "brash"}], "brash_thickness": 1.0}


def test_the_channel_resistance_is_the_rules_formula_worked_by_hand():
    # B 20 m, L 100 m, T 6 m; phi_2 30 deg, alpha 20 deg: psi = atan(tan 30 / sin 20) = 59.35 deg
    hull = BowForm(100.0, 20.0, 6.0, math.radians(30.0), math.radians(20.0), 30.0, 55.0, 400.0)
    hf = 0.26 + math.sqrt(1.0 * 20.0)                      # 4.732 m
    psi = math.degrees(math.atan(math.tan(math.radians(30.0)) / math.sin(math.radians(20.0))))
    assert psi == pytest.approx(59.35, abs=0.01)
    c_mu = 0.15 * math.cos(math.radians(30.0)) + math.sin(math.radians(psi)) * math.sin(math.radians(20.0))
    assert c_mu == pytest.approx(0.424, abs=0.001)          # under the floor: 0.45 counts
    c_psi = 0.047 * psi - 2.115                             # 0.675
    slender = (100.0 * 6.0 / 400.0) ** 3                   # 3.375, raised to the floor of 5
    expected = 845.0 * 0.45 * (hf + 1.0) ** 2 * (20.0 + c_psi * hf) + 42.0 * 55.0 * hf**2 + 825.0 * 5.0 * 400.0 / 100.0
    assert slender < 5.0
    assert brash_channel_resistance(1.0, hull) == pytest.approx(expected, rel=1e-9)
    assert brash_channel_resistance(1.0, hull) == pytest.approx(358.0e3, rel=0.001)  # 289.8 + 51.7 + 16.5 kN
    assert brash_channel_resistance(0.0, hull) == 0.0
    assert brash_channel_resistance(1.5, hull) > brash_channel_resistance(1.0, hull)
    g = 9.81
    assert channel_speed_factor(FSICR_SPEED, 100.0, g) == pytest.approx(1.0)
    assert channel_speed_factor(0.0, 100.0, g) == pytest.approx(1.0 / (1.0 + 9.4 * FSICR_SPEED / math.sqrt(g * 100.0)))


def test_the_keel_load_is_dolgopolovs_worked_by_hand():
    # phi 30 deg: mu_phi = tan 60 deg = sqrt 3; no voids, no cohesion, (rho_w - rho_i) g = 1000 N/m^3:
    # F = 3 h^2 w gamma_e / 2 (1 + h / 6w) = 3 * 25 * 10 * 1000 / 2 * (1 + 5/60) = 406 250 N
    f = keel_resistance(5.0, 10.0, math.radians(30.0), 0.0, 0.0, 1100.0, 1000.0, 10.0)
    assert f == pytest.approx(406250.0, rel=1e-9)
    with_cohesion = keel_resistance(5.0, 10.0, math.radians(30.0), 2000.0, 0.0, 1100.0, 1000.0, 10.0)
    assert with_cohesion - f == pytest.approx(math.sqrt(3.0) * 5.0 * 10.0 * 4000.0 * (1.0 + 5.0 / 60.0), rel=1e-9)
    assert keel_resistance(0.0, 10.0, 0.5, 1e3, 0.3, 1025.0, 900.0, 9.8) == 0.0


def test_ridge_lines_and_the_keel_cross_section():
    ridges = RidgeFieldSettings.model_validate(RIDGES).ridges(60.0, 20.0)
    assert isinstance(ridges, RidgeField)
    lines = ridges.lines()
    assert len(shapely.get_parts(lines)) == 2  # at 500 and 800 m north, each 400 m long
    assert shapely.length(lines) == pytest.approx(800.0)
    assert keel_depth_at(ridges, 50.0, RIDGE_LINE) == pytest.approx(4.5)
    assert keel_depth_at(ridges, 50.0, RIDGE_LINE + 5.0) == pytest.approx(2.25)   # triangular keel
    assert keel_depth_at(ridges, 50.0, RIDGE_LINE - 10.0) == pytest.approx(0.0)
    assert keel_depth_at(ridges, 50.0, 800.0) == pytest.approx(4.5)
    rubble = compile_rubble([], None, (ridges,), 4, 10, 100.0)
    assert rubble.ridge_tile.reshape(10, 4)[:, 0].tolist() == [-1, -1, -1, 0, 0, 0, 0, 0, 0, -1]
    assert rubble_at(rubble, 50.0, RIDGE_LINE)[2:] == (ridges, pytest.approx(4.5))
    assert rubble_at(rubble, 50.0, 200.0)[2:] == (None, 0.0)  # outside the field (a ridge line would lie there)
    assert rubble_at(rubble, 500.0, RIDGE_LINE)[2:] == (None, 0.0)  # off the field


def test_bad_ridge_fields_are_refused_with_the_reason():
    with pytest.raises(ValidationError, match="wider than spacing_m"):
        RidgeFieldSettings.model_validate({**RIDGES, "width_m": 50.0, "spacing_m": 40.0})
    with pytest.raises(ValidationError, match="invalid polygon"):
        RidgeFieldSettings.model_validate({**RIDGES, "polygon_m": [[0, 0], [10, 10], [10, 0], [0, 10]]})
    with pytest.raises(ValidationError, match="keel_depth_m"):
        RidgeFieldSettings.model_validate({**RIDGES, "keel_depth_m": -1.0})


def _world(tmp_path_factory, start_north, regions=(), ridges=()):
    cfg = exercise_config(tmp_path_factory.getbasetemp() / "rubble", 400.0, 900.0, 100.0, start_north=start_north)
    field = cfg.ice_field.model_copy(update={
        "regions": [RegionSettings.model_validate(r) for r in regions],
        "ridges": [RidgeFieldSettings.model_validate(r) for r in ridges]})
    cfg = cfg.model_copy(update={"ice_field": field, "exercise": cfg.exercise.model_copy(
        update={"start_east": 150.0, "start_telegraph": "full_ahead"})})
    model = build_world(cfg, None)
    return model, start_world(model, cfg)


def test_a_ridge_raises_the_ice_load_on_the_hull_by_the_models_amount(tmp_path_factory):
    """The same ship through the same level ice, with and without a ridge: in the keel the
    published ice resistance rises by Dolgopolov's load for the keel depth at the stem (down
    to the draught), within 10 %."""
    start = RIDGE_LINE - 10.0 - 30.0 - 75.0  # the stem (75 m forward of midship) 30 m short of the keel
    ridged, ridged_data = _world(tmp_path_factory, start, ridges=[RIDGES])
    level, level_data = _world(tmp_path_factory, start)
    half_length = ridged.ship.particulars.length / 2.0
    keel = ridged.rubble.ridges[0]
    m = ridged.ice.material
    rises, model_loads = [], []
    for _ in range(250):
        with_ridge, without = step(ridged, ridged_data, 0.1), step(level, level_data, 0.1)
        stem_north = ridged_data.ship.eta[0] + half_length
        depth = 4.5 * max(0.0, 1.0 - 2.0 * abs(stem_north - RIDGE_LINE) / 20.0)
        if depth > 0.5:
            rises.append(with_ridge.ship.ice_resistance - without.ship.ice_resistance)
            model_loads.append(keel_resistance(min(depth, ridged.ship.d), ridged.ship.B, keel.friction_angle,
                                               keel.cohesion, keel.porosity, m.water_density, m.density, m.gravity))
    assert len(rises) > 20, "the stem crossed the keel"
    assert np.mean(model_loads) > 0.5e6
    assert np.mean(rises) == pytest.approx(np.mean(model_loads), rel=0.10)
    assert ridged_data.ship.eta[0] + half_length > RIDGE_LINE + 10.0, "the ship got through the keel"
    assert ridged_data.ship.keel_load == 0.0 and with_ridge.ship.ice_resistance == pytest.approx(
        without.ship.ice_resistance, rel=0.10)


def test_a_brash_channel_is_open_water_that_resists_by_the_rules(tmp_path_factory):
    """A region of brash alone is laid as open water (no floes, no level ice), and a hull in
    it meets the rules' channel resistance times the brash's concentration; outside the
    channel the level ice's, and no brash."""
    model, data = _world(tmp_path_factory, 200.0, regions=[CHANNEL])
    assert model.scene.thickness_at(np.array([150.0, 400.0]), model.scene.tile_class) == 0.0
    assert model.scene.thickness_at(np.array([250.0, 400.0]), model.scene.tile_class) > 0.0
    expected_5kn = 0.9 * brash_channel_resistance(1.0, model.ship.bow)
    broken = 0
    for _ in range(50):
        events = step(model, data, 0.1)
        broken += len(events.broken_by_hull)
    u = data.ship.nu[0]
    assert events.ship.ice_resistance == pytest.approx(
        expected_5kn * channel_speed_factor(u, model.ship.L, model.ice.material.gravity), rel=0.10)
    assert broken == 0, "the channel holds no level ice"
    outside, outside_data = _world(tmp_path_factory, 200.0)  # the same start in level ice
    for _ in range(50):
        level = step(outside, outside_data, 0.1)
    assert outside_data.ship.brash_resistance == 0.0
    assert level.ship.ice_resistance != pytest.approx(events.ship.ice_resistance, rel=0.05)


def _classes(model, data, ctx, pitch_deg=-10.0, yaw_deg=0.0):
    c = ChannelSettings(name="ahead", width=320, height=180, pitch_deg=pitch_deg, yaw_deg=yaw_deg,
                        eye=[20.0, 0.0, 25.0])
    view = WorldView()
    view.apply(snapshot(model, data))
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[c])), [c])
    return cs, view, class_of_pixels(cs.class_images(view)[0])


def test_the_channels_draw_brash_in_the_channel_and_ridge_sails_on_the_ice(tmp_path_factory, ctx):
    """Ahead in the brash channel the sea is mostly brash, drawn as broken ice; level ice
    beside it. A ridge's sail stands on the level ice ahead: its blocks cover the ice
    where the ridge line runs, and the ice there differs from the same view without it."""
    model, data = _world(tmp_path_factory, 200.0, regions=[CHANNEL])
    _, _, cls = _classes(model, data, ctx)
    ahead, near = cls[100:, 120:200], cls[136:]
    ahead, near = ahead[ahead != CLASS_INDEX["own_ship"]], near[near != CLASS_INDEX["own_ship"]]
    assert (ahead == CLASS_INDEX["broken_floe"]).mean() > 0.5  # 9/10 brash
    assert 0.02 < (near == CLASS_INDEX["open_water"]).mean() < 0.3  # near the hull, water between the pieces
    assert (cls[80:100] == CLASS_INDEX["level_ice"]).mean() > 0.2  # on either side of the channel
    start = RIDGE_LINE - 60.0 - 75.0  # the stem 60 m short of the ridge line
    ridged, ridged_data = _world(tmp_path_factory, start, ridges=[RIDGES])
    level, level_data = _world(tmp_path_factory, start)
    with_sail, view, _ = _classes(ridged, ridged_data, ctx, pitch_deg=-5.0)
    assert ridged_data.ship.eta[0] + 75.0 < RIDGE_LINE and with_sail.renderer.sails.tiles, "sails near the eye built"
    without, level_view, _ = _classes(level, level_data, ctx, pitch_deg=-5.0)
    with_sail.render(view)
    without.render(level_view)
    a, b = with_sail.images()[0].astype(float), without.images()[0].astype(float)
    rows = np.abs(a - b).sum(axis=(1, 2))
    assert rows.max() > 0 and np.count_nonzero(rows) < 0.5 * len(rows)  # a band across the view, not the whole


def test_the_bow_rises_in_a_keel_and_settles_after_it(tmp_path_factory):
    """The keel's load lifts the bow (``sim_core.ship.motions``): the ship pitches bow up and
    heaves up while its stem crosses the keel, several times more than in the level ice
    before it, and settles again after it; the outputs carry both."""
    start = RIDGE_LINE - 10.0 - 40.0 - 75.0  # the stem 40 m short of the keel
    model, data = _world(tmp_path_factory, start, ridges=[RIDGES])
    before, during, after = [], [], []
    for _ in range(450):
        events = step(model, data, 0.1)
        stem = data.ship.eta[0] + 75.0
        part = before if stem < RIDGE_LINE - 10.0 else during if stem < RIDGE_LINE + 10.0 else after
        part.append((events.ship.pitch, events.ship.heave))
    assert len(during) > 20 and len(after) > 150
    pitch_before, pitch_during = max(p for p, _ in before), max(p for p, _ in during)
    assert pitch_during > 0.002 and pitch_during > 3.0 * pitch_before, (pitch_before, pitch_during)
    assert max(z for _, z in during) > 0.05  # m up
    assert abs(after[-1][0]) < 0.3 * pitch_during  # settled in the level ice beyond
