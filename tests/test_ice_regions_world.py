"""Level ice and open water from the ice regions in the running world (issue 26, item 1:
level ice stays what it is today, now laid where a chart or region puts it): a tile whose
centre lies in fast ice takes its stage's thickness, one in an ice-free region is open
water: no tile is placed there, the ship meets no ice, and the channels draw sea. A floe
field's tiles take a class of their own, laid from its pack templates
(tests/test_floe_fields_world.py); brash alone is open water that resists as brash does
(tests/test_rubble.py); land is not laid."""
import numpy as np
import pytest
from conftest import exercise_config
from sigrid3_charts import box_ring, write_chart

from bridge_node.charts.field_regions import regions_not_in_the_world
from bridge_node.node.world_setup import build_world, start_position, start_world
from bridge_node.render.channels import ChannelSet
from bridge_node.render.classes import CLASS_INDEX, class_of_pixels
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.stream.world_view import WorldView
from sim_core.regimes.settings import RegionSettings
from sim_core.scene.scene import TileState
from sim_core.ship.resistance import LEVEL_ICE, OPEN_WATER
from sim_core.world import snapshot, step

FAST_ICE = {"name": "fast ice", "polygon_m": [[0.0, 0.0], [400.0, 0.0], [400.0, 600.0], [0.0, 600.0]],
            "concentration": 10, "ice": [{"stage": "medium_first_year", "floe_size": "fast_ice"}]}
LEAD = {"name": "lead", "polygon_m": [[150.0, 0.0], [300.0, 0.0], [300.0, 600.0], [150.0, 600.0]],
        "concentration": 0}  # three tile columns of 50 m, the ship's (centre 225 m) in the middle
PACK = {"name": "pack", "polygon_m": [[0.0, 300.0], [150.0, 300.0], [150.0, 600.0], [0.0, 600.0]],
        "concentration": 7, "ice": [{"stage": "thin_first_year", "floe_size": "small_floe"}]}


def _world(tmp_path_factory, regions):
    cfg = exercise_config(tmp_path_factory.getbasetemp() / "tiles", 400.0, 600.0, 50.0, start_north=-60.0)
    field = cfg.ice_field.model_copy(update={"regions": [RegionSettings.model_validate(r) for r in regions]})
    cfg = cfg.model_copy(update={"ice_field": field})
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    return model, data, cfg


def _steam(model, data, seconds):
    conditions = set()
    for _ in range(int(seconds / 0.1)):
        step(model, data, 0.1)
        if data.ship.eta[0] > 10.0:  # the bow well into the field
            conditions.add(data.ship.ice_condition)
    return conditions


@pytest.fixture(scope="module")
def lead(tmp_path_factory):
    model, data, cfg = _world(tmp_path_factory, [FAST_ICE, LEAD, PACK])
    return model, data, cfg, _steam(model, data, 60.0)


@pytest.fixture(scope="module")
def fast_ice(tmp_path_factory):
    model, data, cfg = _world(tmp_path_factory, [FAST_ICE])
    return model, data, cfg, _steam(model, data, 60.0)


def test_tiles_take_the_regions_thickness(lead):
    model, _, cfg, _ = lead
    scene = model.scene
    h = scene.class_thickness[scene.tile_class].reshape(scene.ny, scene.nx)
    assert np.all(h[:, 3:6] == 0.0)  # the lead: open water
    assert np.all(h[:, 6:] == pytest.approx(0.9)) and np.all(h[:6, :3] == pytest.approx(0.9))  # medium FY, 0.95 m
    pack = scene.tile_class.reshape(scene.ny, scene.nx)[6:, :3]
    assert np.all(h[6:, :3] == pytest.approx(0.5))  # the pack: thin first-year floes, 0.5 m
    assert np.all([model.ice.floe_field[scene.class_templates[k]].all() for k in np.unique(pack)])


def test_in_the_lead_the_ship_meets_no_ice(lead, fast_ice):
    model, data, cfg, conditions = lead
    assert data.ship.eta[0] > 60.0 and abs(data.ship.eta[1] - start_position(model, cfg)[1]) < 10.0
    assert conditions == {OPEN_WATER}
    assert not np.any(data.scene.tile_state == TileState.BREAKABLE) and data.ice.state.n == 0
    ice_model, ice_data, _, ice_conditions = fast_ice
    assert LEVEL_ICE in ice_conditions and np.any(ice_data.scene.tile_state == TileState.BREAKABLE)
    assert data.ship.eta[0] > ice_data.ship.eta[0] + 20.0  # in 0.9 m fast ice it made less way


def test_the_regions_the_world_does_not_lay_are_named(lead, tmp_path):
    _, _, cfg, _ = lead
    assert regions_not_in_the_world(cfg.ice_field, cfg.exercise.origin_deg()) == []
    brash = RegionSettings.model_validate({**PACK, "name": "brash", "concentration": 9,
                                           "ice": [{"stage": "grey_white", "floe_size": "brash"}]})
    chart = write_chart(tmp_path / "land", [(box_ring(20.0, 74.0, 20.01, 74.002), {"POLY_TYPE": "L"})])
    field = cfg.ice_field.model_copy(update={"regions": [*cfg.ice_field.regions, brash], "chart": str(chart)})
    assert regions_not_in_the_world(field, cfg.exercise.origin_deg()) == ["land.shp feature 1"]


def test_the_channels_draw_the_lead_as_sea(lead, ctx):
    model, data, _, _ = lead
    c = ChannelSettings(name="ahead", width=192, height=108, pitch_deg=-12.0, eye=[80.0, 0.0, 20.0])
    view = WorldView()
    view.apply(snapshot(model, data))
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[c])), [c])
    cls = class_of_pixels(cs.class_images(view)[0])
    sea, ice = cls == CLASS_INDEX["open_water"], cls == CLASS_INDEX["level_ice"]
    assert sea[:, 86:106][cls[:, 86:106] != CLASS_INDEX["sky"]].all()  # up the lead to the field's far edge
    assert ice[:, :48].sum() > 20 and ice[:, -48:].sum() > 20  # the fast ice either side of it
