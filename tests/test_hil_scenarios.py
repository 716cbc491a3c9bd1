"""Scenario files, console configs and the judging of expectations, without a node: errors
that name the file, line and key; what a reading series passes or fails."""
import contextlib
import io
import math
import textwrap

import pytest
from conftest import REPO, run_cli

from bridge_node.commands.cli import main
from bridge_node.hil.console_links import AlarmReading, Reading
from bridge_node.hil.player import judge
from bridge_node.hil.scenario import Expectation, load_scenario
from bridge_node.node.config import ConfigError

SCENARIOS = sorted((REPO / "config" / "scenarios").glob("*.toml"))


def test_shipped_scenarios_load():
    names = {load_scenario(p).name for p in SCENARIOS}
    assert len(SCENARIOS) >= 6 and len(names) == len(SCENARIOS)


HEADER = 'name = "typo"\n\n[[actions]]\nat_s = 0.0\nhelm_deg = 5.0\n\n'


@pytest.mark.parametrize("body, line, words", [
    ('[[actions]]\nat_s = 1.0\nhelm = 20.0\n\n[[expect]]\nafter_s = 0\nwithin_s = 1\nalarm = 101\n', 9,
     ["actions.1.helm = 20.0", "unknown key"]),
    ('[[expect]]\nafter_s = 0.0\nwithin_s = "12 s"\nalarm = 101\n', 9, ["expect.0.within_s = '12 s'", "number"]),
    ('[[actions]]\nhelm_deg = 20.0\n\n[[expect]]\nafter_s = 0\nwithin_s = 1\nalarm = 101\n', 7,
     ["actions.1.at_s", "required key is missing"]),
    ('[[faults]]\nat_s = 1.0\nkind = "unplug"\n\n[[expect]]\nafter_s = 0\nwithin_s = 1\nalarm = 101\n', 9,
     ["faults.0.kind = 'unplug'", "disconnect"]),
])
def test_scenario_typos_name_file_line_and_key(tmp_path, body, line, words):
    path = tmp_path / "typo.toml"
    path.write_text(HEADER + body)
    with pytest.raises(ConfigError) as err:
        load_scenario(path)
    assert f"{path}:{line}:" in str(err.value)
    for w in words:
        assert w in str(err.value)


def test_cli_errors_are_one_clear_line(tmp_path):
    """As a user runs it (a process), then the other mistakes through the same entry point."""
    bad = tmp_path / "bad.toml"
    bad.write_text(HEADER + '[[expect]]\nafter_s = 0.0\nwithin_s = 2.0\nquantity = "rudder"\nmin = 1.0\n')
    r = run_cli("hil", "run", str(bad), "--out", str(tmp_path / "out"))
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert f"{bad}:10: expect.0.quantity = 'rudder'" in r.stderr and "rudder_angle" in r.stderr
    handover = tmp_path / "handover_any_kinds.toml"  # the shipped one without its kinds: --links decides
    handover.write_text("\n".join(line for line in (REPO / "config" / "scenarios" / "arbitration_handover.toml")
                                   .read_text().splitlines() if not line.startswith("kinds")))
    handover = str(handover)
    cases = [(["hil", "run", handover], "needs a backup end; give --links PRIMARY,BACKUP"),
             (["hil", "run", handover, "--links", "can,lin"], "--links 'can,lin'")]
    cfg = tmp_path / "console.toml"
    cfg.write_text(f'[[links]]\nrole = "primary"\ntype = "nmea0183"\nport = "{tmp_path}/ttyNONE"\n')
    cases.append((["console", "--config", str(cfg), "--script", str(SCENARIOS[0])],
                  "console end primary (nmea0183): cannot open it: [Errno 2] could not open port"))
    net = tmp_path / "net.toml"
    net.write_text('[[links]]\nrole = "primary"\ntype = "can"\nchannel = "x"\ninterface = "socketcand"\n')
    cases.append((["console", "--config", str(net)], f"{net}:1: links.0.can: interface = 'socketcand' reaches"))
    for argv, words in cases:
        r = cli_in_process(argv + (["--out", str(tmp_path / "out")] if argv[0] == "hil" else []))
        assert r[0] == 2 and words in r[1], (argv, r)


def cli_in_process(argv: list[str]) -> tuple[int, str]:
    """(exit status, standard error) of ``icebridge ARGV`` run in this process."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main(argv)
    return code, err.getvalue()


def expectation(**kw) -> Expectation:
    return Expectation.model_validate({"after_s": 1.0, "within_s": 4.0} | kw)


def rudder(t: float, deg: float, role: str = "panel") -> Reading:
    return Reading(100.0 + t, role, "rudder_angle", math.radians(deg))


RAMP = [rudder(0.1 * k, min(20.0, max(0.0, 2.5 * (0.1 * k - 1.0)))) for k in range(80)]  # 2.5 deg/s from t=1 s


def test_judging_values_rates_holds_and_alarms():
    reach = expectation(quantity="rudder_angle", min=9.0, max=11.0)
    missed = expectation(quantity="rudder_angle", min=19.0, max=21.0, within_s=3.0)
    rate = expectation(quantity="rudder_rate", from_deg=2.0, to_deg=8.0, min=2.32)
    slow = expectation(quantity="rudder_rate", from_deg=2.0, to_deg=18.0, min=2.32, within_s=3.0)
    hold = expectation(quantity="rudder_angle", hold=True, min=-1.0, max=30.0)
    broken = expectation(quantity="rudder_angle", hold=True, min=-1.0, max=5.0)
    raised = expectation(alarm=101, within_s=2.0)
    absent = expectation(alarm=111, state="absent")
    alarms = [AlarmReading(102.5, "panel", 101, True, "every rudder source stale")]
    out = judge([reach, missed, rate, slow, hold, broken, raised, absent], RAMP + alarms, 100.0, 7.9)
    assert [o.passed for o in out] == [True, False, True, False, True, False, True, True]
    assert out[0].elapsed_s == pytest.approx(4.6 - 1.0, abs=0.11)
    assert out[1].measured.startswith("closest 7.50 deg at 3.00 s")  # the window closed at 4 s
    assert out[2].value == pytest.approx(2.5, rel=0.03)
    assert out[3].value == pytest.approx(2.5, rel=0.05) and "from 2 to 7.5 deg" in out[3].measured
    assert "left the band" in out[5].measured
    assert out[6].elapsed_s == pytest.approx(1.5)
    pending = judge([reach, absent], RAMP[:30], 100.0, 3.0)  # t = 3 s: neither decided yet
    assert [o.pending for o in pending] == [True, True]


def test_console_config_roles_are_unique(tmp_path):
    from bridge_node.hil.settings import load_console_config
    cfg = tmp_path / "c.toml"
    cfg.write_text(textwrap.dedent('''
        [[links]]
        role = "primary"
        type = "nmea0183"
        port = "/dev/null"

        [[links]]
        role = "primary"
        type = "modbus"
        port = 5020
        registers = [{ order = "rudder", address = 0 }]
    '''))
    with pytest.raises(ConfigError, match="role.s. .'primary'. given twice"):
        load_console_config(cfg)


def test_a_scenarios_link_kinds_are_one_per_link(tmp_path):
    path = tmp_path / "kinds.toml"
    path.write_text('name = "kinds"\nlinks = ["primary"]\nkinds = ["can", "nmea"]\n\n'
                    '[[expect]]\nafter_s = 0.0\nwithin_s = 1.0\nalarm = 101\n')
    with pytest.raises(ConfigError, match="give one link kind for each of links"):
        load_scenario(path)
    path.write_text(path.read_text().replace('["can", "nmea"]', '["lin"]'))
    with pytest.raises(ConfigError, match="kinds.0 = 'lin'"):
        load_scenario(path)
