"""The instructor lays other ice over an area at run time (issue 26, item 1: regions from
the instructor): ``set_ice`` checked whole and refused with the reason, the world changing
only the ice the ship has not met, the ship meeting the new ice, a floe field laid from its
templates, the change on the state stream (late joiners included) and in the channels."""
import json

import numpy as np
import pytest
from conftest import region_world

from bridge_node.control.client import request
from bridge_node.control.commands import CommandError, command_from_record, command_record, parse_command
from bridge_node.control.endpoint import ControlEndpoint
from bridge_node.control.queue import CommandQueue
from bridge_node.control.settings import ControlSettings
from bridge_node.common.network import free_port
from bridge_node.render.channels import ChannelSet
from bridge_node.render.classes import CLASS_INDEX, class_of_pixels
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.stream.codec import decode, encode
from bridge_node.stream.world_view import WorldView
from sim_core.instructor import Reposition, SetIce
from sim_core.scene.scene import TileState
from sim_core.ship.resistance import LEVEL_ICE, OPEN_WATER
from sim_core.world import snapshot, step

DT = 0.1
PACK = {"name": "pack", "polygon_m": [[0.0, 300.0], [600.0, 300.0], [600.0, 600.0], [0.0, 600.0]],
        "concentration": 7, "ice": [{"stage": "thin_first_year", "floe_size": "small_floe", "concentration": 4},
                                    {"stage": "grey_white", "floe_size": "ice_cake", "concentration": 3}]}
NORTH_BAND = ((0.0, 700.0), (600.0, 700.0), (600.0, 1000.0), (0.0, 1000.0))  # (east, north) m: the last 3 rows


def _world(tmp_path_factory):
    """A 600 m x 1000 m field of 0.5 m ice, 100 m tiles, with a band of 7/10 pack across it
    at 300-600 m north; the ship 80 m south of the field."""
    return region_world(tmp_path_factory.getbasetemp() / "set-ice", 600.0, 1000.0, [PACK], -80.0)


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    return _world(tmp_path_factory)


def _move_to(model, data, north: float, east: float = 350.0) -> None:
    """Move the ship there at once (its tiles built at the switch) and steam on for 2 s."""
    step(model, data, DT, commands=(Reposition(north, east, 0.0, 2.0, at_once=True),))
    for _ in range(20):
        step(model, data, DT)


@pytest.mark.parametrize("message, words", [
    ({"command": "set_ice", "ice": "open water", "polygon_m": [[0, 0], [100, 100], [100, 0], [0, 100]]},
     ["invalid polygon", "Self-intersection"]),
    ({"command": "set_ice", "ice": "open water", "polygon_m": [[0, 0], [100, 0]]}, ["at least 3 corners"]),
    ({"command": "set_ice", "ice": "open water", "polygon_m": [[0, 0], [100, 0], [0, 100]],
      "polygon_deg": [[74, 20], [74.1, 20], [74, 20.1]]}, ["give one polygon"]),
    ({"command": "set_ice", "ice": "open water", "polygon_deg": [[95, 20], [74.1, 20], [74, 20.1]]},
     ["latitudes lie in [-89, 89]"]),
    ({"command": "set_ice", "polygon_m": [[0, 0], [100, 0], [0, 100]]}, ["ice: missing (required)"]),
    ({"command": "set_ice", "ice": "open water", "polygon_m": [[0, 0], [100, 0, 5], [0, 100]]},
     ["polygon_m.1", "at most 2 items"]),
])
def test_a_bad_set_ice_is_refused_naming_what_is_wrong(message, words):
    with pytest.raises(CommandError) as refused:
        parse_command(message)
    for word in words:
        assert word in str(refused.value), str(refused.value)


def test_the_endpoint_refuses_ice_the_exercise_lacks_and_names_what_it_has():
    settings = ControlSettings(endpoint=f"tcp://127.0.0.1:{free_port()}")
    queue = CommandQueue()
    square = [[0.0, 0.0], [100.0, 0.0], [100.0, 100.0], [0.0, 100.0]]
    with ControlEndpoint(settings, queue, dict, ice=("level ice 0.50 m", "open water")) as ep:
        bad = request(settings.endpoint, {"command": {"command": "set_ice", "ice": "fast ice", "polygon_m": square}},
                      None)
        good = request(settings.endpoint, {"command": {"command": "set_ice", "ice": "open water",
                                                       "polygon_m": square}}, None)
    assert not bad["ok"] and 'ice = "fast ice"' in bad["error"] and '"open water"' in bad["error"]
    assert good == {"ok": True, "queued": "set_ice"}
    assert len(queue._waiting) == 1 and ep.counts["invalid"] == 1


def test_the_exercise_offers_its_own_ice_and_open_water(world):
    model, _ = world
    assert model.scene.class_names == ("level ice 0.50 m", "7/10: 4/10 thin_first_year small_floe, 3/10 grey_white "
                                       "ice_cake", "open water")
    assert model.scene.class_thickness[-1] == 0.0 and len(model.scene.class_templates[-1]) == 0


def test_only_ice_the_ship_has_not_met_changes(tmp_path_factory):
    model, data = _world(tmp_path_factory)
    for _ in range(100):  # 10 s into the field: tiles placed around the bow
        step(model, data, DT)
    placed = np.flatnonzero(data.scene.tile_state != TileState.UNBREAKABLE)
    everything = ((-10.0, -10.0), (610.0, -10.0), (610.0, 1010.0), (-10.0, 1010.0))
    events = step(model, data, DT, commands=(SetIce(everything, "open water"),))
    changed = events.retiled["tile"]
    assert len(placed) and not np.isin(placed, changed).any()  # the broken ice stays
    near = data.scene.tile_class == model.scene.tile_class
    assert near.sum() > len(placed)  # and so do the tiles about to be switched in around the hull
    assert np.all(data.scene.tile_class[changed] == model.scene.class_names.index("open water")) and len(changed) > 30
    assert np.array_equal(np.sort(changed), np.flatnonzero(~near))
    assert events.commands == (SetIce(everything, "open water"),)


def test_the_ship_meets_open_water_laid_ahead_and_level_ice_without(tmp_path_factory):
    conditions = {}
    for lay in (False, True):
        model, data = _world(tmp_path_factory)
        if lay:
            step(model, data, DT, commands=(SetIce(NORTH_BAND, "open water"),))
        _move_to(model, data, 800.0)
        tile = 8 * model.scene.nx + 3
        conditions[lay] = data.ship.ice_condition, data.ship.ice_h, TileState(data.scene.tile_state[tile])
    assert conditions[False] == (LEVEL_ICE, 0.5, TileState.BREAKABLE)
    assert conditions[True] == (OPEN_WATER, 0.0, TileState.UNBREAKABLE)  # open water is never placed


def test_a_floe_field_laid_over_level_ice_is_placed_from_its_templates(tmp_path_factory):
    model, data = _world(tmp_path_factory)
    pack = next(name for name in model.scene.class_names if name.startswith("7/10"))
    step(model, data, DT, commands=(SetIce(NORTH_BAND, pack),))
    _move_to(model, data, 850.0)
    placed = {t: k for t, k in data.scene.placement.items()}
    in_band = [k for t, k in placed.items() if t // model.scene.nx >= 7]
    below = [k for t, k in placed.items() if t // model.scene.nx < 7]
    assert len(in_band) >= 3 and len(below) >= 1
    assert all(model.ice.floe_field[data.ice.tiles.template[k]] for k in in_band)
    assert not any(model.ice.floe_field[data.ice.tiles.template[k]] for k in below)  # row 6: level, as laid


def test_on_a_drifting_field_the_area_is_where_the_ice_lies_now(tmp_path_factory):
    model, data = _world(tmp_path_factory)
    data.ice_frame.offset[:] = (200.0, 0.0)  # the field has drifted 200 m east
    step(model, data, DT, commands=(SetIce(NORTH_BAND, "open water"),))
    changed = np.flatnonzero(data.scene.tile_class != model.scene.tile_class)
    columns = set((changed % model.scene.nx).tolist())
    assert columns == {0, 1, 2, 3}  # world east 200-600 m: the field's first four columns now


def test_the_stream_carries_the_new_ice_to_late_joiners(world):
    model, data = world
    events = step(model, data, DT, commands=(SetIce(NORTH_BAND, "open water"),))
    decoded, _, _ = decode(encode(events))
    assert np.array_equal(decoded.retiled, events.retiled) and len(decoded.retiled) == 18
    assert decoded.commands == events.commands
    old = encode(events)  # a recording made before the field: one array fewer
    header = json.loads(old[1])
    header["arrays"].pop()
    older, _, _ = decode([old[0], json.dumps(header).encode(), *old[2:-2], old[-1]])
    assert len(older.retiled) == 0
    view = WorldView()
    view.apply(snapshot(model, data))
    assert view.retiled == {int(t): model.scene.class_names.index("open water") for t in events.retiled["tile"]}
    assert sorted(view.take_changes().retiled) == sorted(events.retiled["tile"].tolist())
    late = WorldView()
    late.apply(view.to_snapshot())
    assert late.retiled == view.retiled
    record = command_record(events.commands[0])
    assert command_from_record(record) == events.commands[0]
    for bad in ({"polygon": [[0.0, 0.0], [1.0, 1.0]]}, {"polygon": []}, {"ice": 3},
                {"polygon": [[0, 0], [100, 100], [100, 0], [0, 100]]}):
        with pytest.raises(CommandError, match="not a command record"):
            command_from_record({**record, **bad})
    assert step(model, data, DT, commands=(SetIce(NORTH_BAND, "fast ice"),)).commands == ()  # ice it lacks: nothing


def test_the_channel_shows_open_water_where_the_ice_was_taken(tmp_path_factory, ctx):
    model, data = _world(tmp_path_factory)
    _move_to(model, data, 560.0)  # the bow at 635 m north, in the level ice past the pack
    c = ChannelSettings(name="ahead", width=240, height=135, pitch_deg=-6.0, eye=[20.0, 0.0, 25.0])
    renderer = SceneRenderer(ctx, model, RenderSettings(channels=[c]))
    channels = ChannelSet(renderer, [c])
    view = WorldView()
    view.apply(snapshot(model, data))
    water = []
    for lay in (False, True):
        if lay:
            view.apply(step(model, data, DT, commands=(SetIce(NORTH_BAND, "open water"),)))
        cls = class_of_pixels(channels.class_images(view)[0])
        water.append((cls[40:90] == CLASS_INDEX["open_water"]).mean())
    assert water[1] > water[0] + 0.2, water  # the band ahead, 70-370 m on, is water now
