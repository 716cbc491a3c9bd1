"""Device errors that say why: the OS's or python-can's own message in the link-down alarm
and the log, and an unknown python-can interface rejected when the config loads."""
import logging
import time

import pytest
from links_helpers import STATE, node_config, tick

from bridge_node.links.hub import LINK_DOWN_ALARM, LinkHub
from bridge_node.node.config import ConfigError, load_config


def down_alarm(links: list[dict], caplog) -> tuple[str, dict, list[str]]:
    """Open a hub on these links, tick it for 0.5 s: the link-down alarm's text, the link's
    health and the warnings logged about its device."""
    cfg = node_config(links, rudder=[links[0]["name"]])
    with caplog.at_level(logging.WARNING, logger="icebridge.links"), LinkHub(cfg.links, cfg.arbitration) as hub:
        end = time.monotonic() + 0.5
        while time.monotonic() < end:  # retried with back-off: 0.1, 0.2 s
            tick(hub, STATE, time.monotonic())
            time.sleep(0.01)
        health = hub.links[0].health().as_dict()
        text = hub.active_alarms[LINK_DOWN_ALARM].text
    name = links[0]["name"]
    return text, health, [r.getMessage() for r in caplog.records if r.getMessage().startswith(f"link {name}: ")]


def test_missing_serial_port(tmp_path, caplog):
    port = str(tmp_path / "ttyUSB9")
    text, health, logged = down_alarm([{"type": "nmea0183", "name": "helm", "port": port}], caplog)
    assert text == "link helm down: No such file or directory"
    assert health["errors"]["open_failed"] >= 2 and f"could not open port {port}" in health["last_error"]
    assert logged == [f"link helm: {health['last_error']}"]  # once, not at every retry


def test_slcan_adapter_missing(tmp_path, caplog):
    channel = str(tmp_path / "ttyACM9")
    text, health, logged = down_alarm([{"type": "can", "name": "can", "interface": "slcan", "channel": channel,
                                        "allowed_sources": [0x42]}], caplog)
    assert text == "link can down: No such file or directory"
    assert channel in health["last_error"] and len(logged) == 1


def test_can_interface_the_os_lacks(caplog):
    """socketcan needs the kernel's CAN support: where it is missing (this machine) or the
    interface is, the OS's own error; too long for ALR whole, its errno name is used."""
    text, health, logged = down_alarm([{"type": "can", "name": "can", "interface": "socketcan",
                                        "channel": "vcan9", "allowed_sources": [0x42]}], caplog)
    reason = text.removeprefix("link can down: ")
    assert reason != text and reason in health["last_error"] + " ENODEV EAFNOSUPPORT"
    assert reason in ("No such device", "ENODEV", "EAFNOSUPPORT") and len(logged) == 1


def test_driver_python_can_cannot_load(caplog):
    """kvaser without Kvaser's canlib: python-can fails inside the driver (a NameError); the
    node keeps running, with python-can's message in the log."""
    text, health, logged = down_alarm([{"type": "can", "name": "kv", "interface": "kvaser", "channel": "0",
                                        "allowed_sources": [0x42]}], caplog)
    assert text.startswith("link kv down")
    assert "python-can cannot start interface 'kvaser'" in health["last_error"] and len(logged) == 1


def test_unknown_interface_rejected_when_the_config_loads(tmp_path):
    cfg = tmp_path / "node.toml"
    cfg.write_text('[ship]\nname = "polar_cargo"\n[[links]]\nname = "can"\ntype = "can"\ninterface = "slcn"\n'
                   'channel = "/dev/ttyACM0"\nallowed_sources = [66]\n')
    with pytest.raises(ConfigError) as err:
        load_config(cfg)
    message = str(err.value)
    assert str(cfg) in message and "links.0.interface" in message
    assert "python-can has no interface 'slcn'" in message and "slcan" in message
