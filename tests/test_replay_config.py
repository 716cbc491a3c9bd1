"""A session record that keeps its run's node config (``node.toml``) replays with it without
``--config``: its console link, which the default config lacks, gives the orders again, and
the replay ends where the run did."""
import json
import threading

import serial
import tomli_w
from conftest import exercise_config, free_port, run_cli
from links_helpers import pty_pair
from replay_logs import sentence

from bridge_node.links.hub import LinkHub
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.replay.session import NODE_CONFIG, recorded_config


def _helm(port: str, stop: threading.Event) -> None:
    """The console on NMEA 0183: starboard 20, repeated."""
    with serial.Serial(port, 38400, timeout=0) as line:
        while not stop.is_set():
            line.write((sentence("RCROR,20.0,A,,V,B") + "\r\n").encode())
            stop.wait(0.1)


def test_a_record_replays_with_the_node_config_it_keeps(tmp_path):
    with pty_pair(tmp_path) as (node_end, console_end):
        base = exercise_config(tmp_path / "tiles", 300.0, 300.0, 50.0, start_north=-60.0)
        cfg = type(base).model_validate(base.model_dump() | {
            "links": [{"type": "nmea0183", "name": "console", "port": node_end, "udp_output": False}],
            "arbitration": {"rudder": ["console"], "fail_safe": "hold"},
            "stream": {"publish": f"tcp://127.0.0.1:{free_port()}", "snapshot": f"tcp://127.0.0.1:{free_port()}"}})
        model = build_world(cfg, None)
        live = start_world(model, cfg)
        record, stop, last = tmp_path / "session", threading.Event(), {}
        helm = threading.Thread(target=_helm, args=(console_end, stop), daemon=True)
        with LinkHub(cfg.links, cfg.arbitration, record) as hub:
            helm.start()
            try:
                run_realtime(model, live, hub, cfg.realtime.rate_hz, None,
                             [lambda outcome: last.update(ship=outcome.events.ship)],
                             should_stop=lambda: live.time >= 2.0 - 1e-9)
            finally:
                stop.set()
                helm.join(2.0)
    # as the run writes it: the config the run used, without the console process's settings
    node = cfg.model_dump(exclude_none=True, exclude={"console"})
    (record / NODE_CONFIG).write_text(tomli_w.dumps(node), encoding="utf-8")
    assert recorded_config([str(record)]) == record / NODE_CONFIG
    assert recorded_config([str(record / "nmea.log")]) == record / NODE_CONFIG
    assert recorded_config([str(tmp_path / "tiles")]) is None  # not a session record

    r = run_cli("replay", str(record), "--max", "--render", "none", "--json", "--out", str(tmp_path / "replay"))
    assert r.returncode == 0, r.stderr
    replay = json.loads(r.stdout.splitlines()[-1])
    assert replay["config"] == str(record / NODE_CONFIG)
    assert replay["input"]["exact"] and replay["input"]["orders"]["console/rudder/0"] > 0
    ship = last["ship"]
    assert replay["end"] == {"north_m": round(ship.north, 1), "east_m": round(ship.east, 1)}
