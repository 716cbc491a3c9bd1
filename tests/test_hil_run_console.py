"""The run's software console (``[console]``, the default config's demo): ``icebridge run``
starts ``icebridge console`` in its own process over a real link (slcan on a socat pty
pair, Modbus TCP on 127.0.0.1), the ship obeys its script, the run summary says how the
script's expectations went, and the session record replays the run exactly. What a user can get wrong is a clear error."""
import json
import os
import subprocess
import sys

import pytest
from conftest import REPO, free_port, run_cli

DEMO = REPO / "config" / "scenarios" / "demo_voyage.toml"


def node_toml(folder, console: str) -> str:
    """A small exercise (400 m field of 0.3 m ice, the ship south of it) with a ``[console]`` body."""
    path = folder / "node.toml"
    path.write_text('[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 400.0\nheight = 400.0\nthickness = 0.3\n'
                    f'[paths]\ncache_dir = "{folder / "tiles"}"\nsession_dir = "{folder / "sessions"}"\n'
                    f'[stream]\npublish = "tcp://127.0.0.1:{free_port()}"\n'
                    f'snapshot = "tcp://127.0.0.1:{free_port()}"\n'
                    f'[control]\nendpoint = "tcp://127.0.0.1:{free_port()}"\n[console]\n{console}\n')
    return str(path)


@pytest.mark.parametrize("link", ["can", "modbus"])
def test_the_console_process_gives_the_run_its_orders(tmp_path, link):
    cfg = node_toml(tmp_path, f'script = "{DEMO}"\nlink = "{link}"')
    r = run_cli("run", "--config", cfg, "--duration", "30", "--render", "none", "--json", "--out", str(tmp_path / "out"))
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["console"]["result"] == "3 of 3 expectations met" and out["console"]["passed"], \
        (tmp_path / "out" / "console.log").read_text()
    console = next(x for x in out["links"] if x["name"] == "console")
    assert console["connected"] and console["inputs"] > 0
    assert set(console["errors"]) <= {"connect_failed"}  # Modbus: tries before the console's server was up
    assert out["alarms"] == []  # held to the end: never stale, no fail-safe
    log = (tmp_path / "out" / "console.log").read_text()
    assert "PASS  demo voyage" in log and "holding the last orders" in log
    # the orders went over the wire: the session record holds the console link's traffic
    record = next((tmp_path / "sessions").iterdir())
    assert (record / ("can.log" if link == "can" else "modbus.csv")).stat().st_size > 0
    # and the node config the run used, with which the record is re-simulated exactly
    r = run_cli("replay", str(record), "--config", str(record / "node.toml"), "--max", "--render", "none", "--json",
                "--out", str(tmp_path / "replay"))
    assert r.returncode == 0, r.stderr
    replay = json.loads(r.stdout.splitlines()[-1])
    assert replay["input"]["exact"] and replay["input"]["orders"]["console/rudder/0"] > 0
    assert replay["end"] == {"north_m": out["north_m"], "east_m": out["east_m"]}


def test_a_missing_socat_is_a_clear_error_naming_the_way_out(tmp_path):
    cfg = node_toml(tmp_path, f'script = "{DEMO}"\nlink = "can"')
    env = os.environ | {"PATH": str(tmp_path)}  # no socat on it
    r = subprocess.run([sys.executable, "-m", "bridge_node", "run", "--config", cfg, "--duration", "5", "--render",
                        "none", "--out", str(tmp_path / "out")], capture_output=True, text=True, cwd=REPO, env=env,
                       timeout=120)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert f"{cfg}: console.link = 'can'" in r.stderr and "socat is missing" in r.stderr
    assert 'link = "modbus"' in r.stderr


def test_console_mistakes_name_the_file_and_key(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[[actions]]\nat_s = 1.0\nhelm = 10.0\n[[expect]]\nafter_s = 0.0\nwithin_s = 1.0\n'
                   'quantity = "rudder_angle"\nmin = 0.0\n')
    cases = [(f'script = "{bad}"', f"{bad}:4: actions.0.helm"),
             ('script = "no_such.toml"', "console.script = 'no_such.toml': no such file"),
             (f'script = "{DEMO}"\nlink = "lin"', "console.link = 'lin'")]
    for body, message in cases:
        cfg = node_toml(tmp_path, body)
        r = run_cli("run", "--config", cfg, "--duration", "5", "--render", "none", "--out", str(tmp_path / "out"))
        assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr, r.stderr
