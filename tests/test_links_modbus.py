"""Modbus link against a real pymodbus server playing the console: TCP on 127.0.0.1 and RTU
over a pty pair; the server dies mid-run and comes back."""
import math
import time
from contextlib import ExitStack

import pytest

from bridge_node.link_hub import LINK_DOWN_ALARM, LinkHub
from bridge_node.order_arbiter import ALARM_NUMBERS
from links_helpers import node_config, order_collector, pty_pair, wait_for
from modbus_console import ModbusConsole
from test_links_can import STATE

REGISTERS = [{"order": "rudder", "address": 0, "scale": 0.1}, {"order": "lever", "address": 1},
             {"order": "telegraph", "address": 2, "type": "uint16"}]
WRITES = [{"value": "rudder_angle", "address": 10, "scale": 0.1}, {"value": "shaft_rpm", "address": 11, "scale": 1.0}]


def modbus_setup(stack: ExitStack, transport: str, tmp_path):
    if transport == "tcp":
        console = ModbusConsole("tcp")
        link = {"type": "modbus", "name": "io", "port": console.port}
    else:
        server_end, node_end = stack.enter_context(pty_pair(tmp_path))
        console = ModbusConsole("rtu", serial_port=server_end)
        link = {"type": "modbus", "name": "io", "transport": "rtu", "serial_port": node_end, "baudrate": 38400}
    console.set(0, -155)  # -15.5 deg
    console.set(2, 4)  # ETL 04: full ahead
    console.start()
    stack.callback(console.stop)
    cfg = node_config([link | {"registers": REGISTERS, "writes": WRITES, "poll_hz": 20, "timeout_s": 0.5}],
                      rudder=["io"], engine=["io"], fail_safe="midships_stop", fail_safe_after_s=0.5)
    hub = LinkHub(cfg, None)
    hub.open()
    stack.callback(hub.close)
    return console, hub


@pytest.mark.parametrize("transport", ["tcp", "rtu"])
def test_console_registers_read_and_indicators_written(tmp_path, transport):
    with ExitStack() as stack:
        console, hub = modbus_setup(stack, transport, tmp_path)
        got, tick = order_collector(hub, STATE)
        wait_for(lambda: "rudder" in got and "telegraph" in got, poll=tick)
        assert got["rudder"] == pytest.approx(math.radians(-15.5))
        assert got["telegraph"] == "full_ahead"
        wait_for(lambda: console.get(10) != 0, poll=tick)
        assert console.get(10) == (-123) & 0xFFFF  # -12.3 deg in 0.1 deg
        assert console.get(11) == round(STATE.shaft_rps * 60)


@pytest.mark.parametrize("transport", ["tcp", "rtu"])
def test_server_lost_alarm_fail_safe_and_recovery(tmp_path, transport):
    with ExitStack() as stack:
        console, hub = modbus_setup(stack, transport, tmp_path)
        decisions = []

        def tick():
            decisions.append(hub.tick(STATE, time.monotonic()))
        wait_for(lambda: decisions and decisions[-1].active["rudder"] == "io", poll=tick)
        console.stop()
        wait_for(lambda: any(d.controls.rudder == 0.0 for d in decisions), timeout=5.0, poll=tick)
        fail_safe = [d for d in decisions if d.controls.rudder == 0.0][0]
        assert fail_safe.controls.telegraph == "stop"  # midships and stop
        stale, failed = ALARM_NUMBERS["rudder"]
        assert {stale, failed, LINK_DOWN_ALARM} <= set(hub.active_alarms)
        console.set(0, 100)  # the console came back with a new order: 10 deg to starboard
        console.start()
        took = wait_for(lambda: decisions[-1].controls.rudder is not None and decisions[-1].controls.rudder > 0,
                        timeout=5.0, poll=tick)
        assert took < 2.0
        assert decisions[-1].controls.rudder == pytest.approx(math.radians(10.0))
        assert not hub.active_alarms  # every alarm cleared
        assert hub.links[0].health().reconnects >= 1
