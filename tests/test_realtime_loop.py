"""The node's real-time loop end to end: a console on virtual CAN steers the ship through the
ice world, and the instruments see the result."""
import math
import threading

import can
import pytest
from nmea2000.decoder import NMEA2000Decoder

from bridge_node.config import load_config
from bridge_node.link_hub import LinkHub
from bridge_node.realtime_loop import run_realtime
from bridge_node.world_setup import build_world, start_world
from sim_core.floe_state import FREE
from test_links_can import console_frame


def test_console_steers_the_ship_in_real_time(tmp_path):
    base = load_config()
    cfg = base.model_copy(update={
        "ice_field": base.ice_field.model_copy(update={"width": 400.0, "height": 400.0}),
        "links": [], "paths": base.paths.model_copy(update={"cache_dir": str(tmp_path / "tiles")}),
    })
    cfg = type(cfg).model_validate(cfg.model_dump() | {
        "links": [{"type": "can", "name": "helm", "channel": "icebridge-rt"}],
        "arbitration": {"rudder": ["helm"], "engine": ["helm"]},
        "exercise": cfg.exercise.model_dump() | {"start_north": -60.0}})  # bow already in the ice
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    hub = LinkHub(cfg, None)
    hub.open()
    console = can.Bus(interface="virtual", channel="icebridge-rt")
    stop = threading.Event()

    def helm() -> None:
        while not stop.is_set():
            console.send(console_frame("HelmOrder", RudderOrder=35.0, Status=1, Counter=0))
            stop.wait(0.1)
    sender = threading.Thread(target=helm, daemon=True)
    sender.start()
    try:
        psi0 = data.ship.eta[5]
        stats = run_realtime(model, data, hub, 30.0, 3.0, (1.29, 0.35))
    finally:
        stop.set()
        sender.join(2.0)
        hub.close()
    assert 80 <= stats.ticks <= 92  # 30 Hz for 3 s
    assert stats.summary()["real_time_factor"] > 0.75  # the first tick places the tiles around the bow
    assert data.ship.rudder > math.radians(5.0)  # the steering gear follows the console
    assert data.ship.eta[5] > psi0  # and the ship swings to starboard
    assert data.ice.state.count(FREE) > 0  # through ice it breaks
    heading = None
    dec = NMEA2000Decoder()
    while (msg := console.recv(timeout=0.05)) is not None:
        m = dec.decode(msg)
        if m is not None and m.PGN == 127250:
            heading = {f.id: f.value for f in m.fields}["heading"]
    console.shutdown()
    assert heading == pytest.approx(data.ship.eta[5] % (2 * math.pi), abs=0.01)  # last published state
