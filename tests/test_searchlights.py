"""Searchlights steered from the console: the software console's order on each link (CAN on
python-can's virtual bus, NMEA 0183 over a pty pair, Modbus TCP from its register server on
127.0.0.1) decoded by the node's links and passed on by the arbiter, an out-of-range order
counted and dropped; the world refusing an aim beyond the mount's train range; the
published state reaching a late joiner of the state stream, whose night picture is lit on
the side the light is trained to."""
import dataclasses
import itertools
import math
import time
from contextlib import ExitStack

import numpy as np
import pytest
from conftest import exercise_toml, free_port
from links_helpers import STATE, node_config, pty_pair, wait_for

from bridge_node.hil.console_links import Order
from bridge_node.hil.console_registry import make_console_link
from bridge_node.hil.scenario import Action
from bridge_node.hil.settings import ConsoleConfig
from bridge_node.links.hub import LinkHub
from bridge_node.node.config import load_config
from bridge_node.exercise.order_refusals import OrderRefusals
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet, create_context
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings
from bridge_node.replay.session import SessionSource, read_session
from bridge_node.stream.publisher import StatePublisher
from bridge_node.stream.subscriber import StateSubscriber
from sim_core.ship.orders import OrderKind
from sim_core.ship.searchlights import SearchlightMount, SearchlightOrder, SearchlightState, order_searchlight
from sim_core.world import Controls, step

AIM = SearchlightOrder(1, True, math.radians(-30.0), math.radians(-8.0))  # light 1, 30 deg to port, 8 deg down
FAR = dataclasses.replace(AIM, bearing=math.radians(200.0))  # beyond any bearing
REGISTERS = [{"order": "rudder", "address": 0, "type": "int16", "scale": 0.1},
             {"order": "searchlight_on", "light": 1, "address": 4, "type": "uint16", "scale": 1.0},
             {"order": "searchlight_bearing", "light": 1, "address": 5, "type": "int16", "scale": 0.1},
             {"order": "searchlight_elevation", "light": 1, "address": 6, "type": "int16", "scale": 0.1}]
_channels = itertools.count()


@pytest.fixture(params=["can", "nmea0183", "modbus"])
def wired(request, tmp_path):
    """(node hub recording to tmp_path/record, console end, node config) of one link kind, both open."""
    kind = request.param
    with ExitStack() as stack:
        if kind == "can":
            channel = f"searchlight-{next(_channels)}"
            node = {"interface": "virtual", "channel": channel, "allowed_sources": [0x42]}
            console = {"interface": "virtual", "channel": channel}
        elif kind == "nmea0183":
            a, b = stack.enter_context(pty_pair(tmp_path))
            node, console = {"port": a}, {"port": b}
        else:
            port = free_port()
            node = {"port": port, "poll_hz": 50.0, "registers": REGISTERS}
            console = {"port": port, "registers": REGISTERS}
        end = make_console_link(ConsoleConfig.model_validate(
            {"links": [{"role": "primary", "type": kind, **console}]}).links[0])
        stack.enter_context(end)
        cfg = node_config([{"name": "console", "type": kind, **node}], rudder=["console"])
        hub = stack.enter_context(LinkHub(cfg.links, cfg.arbitration, tmp_path / "record"))
        yield hub, end, cfg


def passed_on(hub: LinkHub, end, order: SearchlightOrder, seconds: float) -> list[SearchlightOrder]:
    """The searchlight orders the node passes on within ``seconds`` of the console giving ``order``."""
    got = []

    def tick() -> None:
        now = time.monotonic()
        end.tick(now)
        got.extend(hub.poll(now).controls.searchlights)
        hub.publish(STATE, now)

    end.order(Order(OrderKind.SEARCHLIGHT, order), time.monotonic())
    with pytest.raises(AssertionError):
        wait_for(lambda: False, timeout=seconds, poll=tick)
    return got


def commanded(orders: list[SearchlightOrder]) -> SearchlightState:
    """Light 1's state after the orders, from off, ahead and level."""
    mount = SearchlightMount(SearchlightState(False, 0.0, 0.0), (-math.pi, math.pi), (-math.pi / 2, math.pi / 2))
    states = [mount.default] * 2
    for order in orders:
        assert order_searchlight((mount, mount), states, order) is None
    return states[1]


def test_each_link_decodes_the_consoles_searchlight_order_and_counts_one_out_of_range(wired, tmp_path):
    hub, end, cfg = wired
    wait_for(lambda: hub.links[0].connected, poll=lambda: hub.poll(time.monotonic()))
    got = passed_on(hub, end, AIM, 1.0)
    state = commanded(got)
    assert got and state.on and {o.index for o in got} == {1}
    assert (state.bearing, state.elevation) == pytest.approx((AIM.bearing, AIM.elevation), abs=1e-6)
    refused = passed_on(hub, end, FAR, 0.6)
    assert hub.errors()["out_of_range"] >= 1
    assert all(o.bearing is None or abs(o.bearing) <= math.pi for o in refused)  # Modbus: on and elevation still pass
    hub.close()
    folder = tmp_path / "record"
    session = read_session(folder, {p.name for p in folder.iterdir()}, 0.05)
    with SessionSource(cfg.links, cfg.arbitration, session) as source:  # the record re-simulated: the same orders again
        replayed = [o for k in range(source.steps) for o in source.inputs(k)[0].searchlights]
    assert commanded(replayed) == commanded(got + refused) and replayed


def test_a_scenario_action_gives_a_searchlight_order():
    action = Action.model_validate({"at_s": 1.0, "searchlight": {"light": 2, "on": False, "bearing_deg": 45.0,
                                                                 "elevation_deg": -5.0}})
    assert action.searchlight.light == 2
    with pytest.raises(ValueError, match="exactly one of"):
        Action.model_validate({"at_s": 1.0, "helm_deg": 5.0, "searchlight": {"light": 0, "bearing_deg": 0.0,
                                                                             "elevation_deg": 0.0}})


LIGHT = ('[[render.searchlights]]\nposition = [20.0, 0.0, 30.0]\ndepression_deg = 10.0\n'
         'train_range_deg = [-90.0, 90.0]\non = false\n')
W, H = 192, 108
AHEAD = ChannelSettings(name="ahead", width=W, height=H, pitch_deg=-8.0, eye=[10.0, 0.0, 25.0])


@pytest.fixture(scope="module")
def exercise(tmp_path_factory):
    folder = tmp_path_factory.mktemp("searchlight")
    path = exercise_toml(folder, LIGHT, render='start_utc = 2026-12-21T22:00:00+00:00')  # polar night
    cfg = load_config(path)
    return cfg, build_world(cfg, str(path))


def aimed(bearing_deg: float) -> Controls:
    return Controls(searchlights=(SearchlightOrder(0, True, math.radians(bearing_deg), math.radians(-10.0)),))


def test_the_world_publishes_the_order_and_refuses_one_beyond_the_train_range(exercise):
    cfg, model = exercise
    data = start_world(model, cfg)
    assert step(model, data, 0.1).ship.searchlights == (SearchlightState(False, 0.0, math.radians(-10.0)),)  # config
    events = step(model, data, 0.1, aimed(25.0))
    assert events.ship.searchlights == (SearchlightState(True, math.radians(25.0), math.radians(-10.0)),)
    events = step(model, data, 0.1, aimed(120.0))
    [refused] = events.rejected
    assert refused.order == "searchlight" and refused.refused and "outside -90..90 deg" in refused.text
    assert events.ship.searchlights[0].bearing == pytest.approx(math.radians(25.0))  # the last aim held
    refusals = OrderRefusals()
    assert refusals.note(events.rejected, 0.0) == [] and refusals.counts["searchlight refused"] == 1
    assert step(model, data, 0.1, Controls(searchlights=(SearchlightOrder(3, True),))).rejected[0].refused


def night_picture(model, cfg, view) -> np.ndarray:
    """Luminance of the ahead channel, the ship moved onto the level ice (north 200 m)."""
    view.ship = dataclasses.replace(view.ship, north=200.0, east=200.0, heading=0.0)
    cs = ChannelSet(SceneRenderer(create_context(), model, cfg.render.model_copy(update={"channels": [AHEAD]})),
                    [AHEAD])
    cs.render(view)
    return cs.images()[0].astype(float) @ np.array([0.2126, 0.7152, 0.0722])


def test_a_late_joiner_sees_the_light_trained_to_starboard_then_to_port(exercise):
    cfg, model = exercise
    data = start_world(model, cfg)
    halves = {}
    with StatePublisher(cfg.stream) as publisher:
        for bearing in (25.0, -25.0, None):
            publisher.publish(step(model, data, 0.1, aimed(bearing) if bearing is not None else
                                   Controls(searchlights=(SearchlightOrder(0, on=False),))))
            with StateSubscriber(cfg.stream.publish, cfg.stream.snapshot) as late:
                late.sync()
                lum = night_picture(model, cfg, late.view)
            lit = lum > 30.0
            halves[bearing] = int(lit[:, :W // 2].sum()), int(lit[:, W // 2:].sum())
    assert halves[25.0][1] > 100 and halves[25.0][0] < 0.05 * halves[25.0][1], halves  # lit pixels, port | starboard
    assert halves[-25.0][0] > 100 and halves[-25.0][1] < 0.05 * halves[-25.0][0], halves
    assert halves[None] == (0, 0), halves  # switched off: the night is dark
