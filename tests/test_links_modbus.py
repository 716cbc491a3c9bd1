"""Modbus link against a real pymodbus server playing the console: TCP on 127.0.0.1 and RTU
over a pty pair; the server dies mid-run and comes back."""
import math
import random
import time
from contextlib import ExitStack

import pytest
from conftest import free_port
from links_helpers import STATE, node_config, order_collector, pty_pair, tick, wait_for
from modbus_console import ModbusConsole

from bridge_node.hil.console_modbus import ModbusConsole as ConsoleModbus
from bridge_node.hil.console_links import Order
from bridge_node.hil.scenario import Fault
from bridge_node.hil.settings import ModbusConsoleSettings
from bridge_node.links.arbiter import ALARM_NUMBERS
from bridge_node.links.hub import LINK_DOWN_ALARM, LinkHub
from sim_core.ship.orders import OrderKind

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
    hub = LinkHub(cfg.links, cfg.arbitration)
    hub.open()
    stack.callback(hub.close)
    return console, hub


@pytest.mark.parametrize("transport", ["tcp", "rtu"])
def test_console_registers_read_and_indicators_written(tmp_path, transport):
    with ExitStack() as stack:
        console, hub = modbus_setup(stack, transport, tmp_path)
        got, collect = order_collector(hub, STATE)
        wait_for(lambda: "rudder" in got and "telegraph" in got, poll=collect)
        assert got["rudder"] == pytest.approx(math.radians(-15.5))
        assert got["telegraph"] == "full_ahead"
        wait_for(lambda: console.get(10) != 0, poll=collect)
        assert console.get(10) == (-123) & 0xFFFF  # -12.3 deg in 0.1 deg
        assert console.get(11) == round(STATE.shaft_rps * 60)


@pytest.mark.parametrize("transport", ["tcp", "rtu"])
def test_server_lost_alarm_fail_safe_and_recovery(tmp_path, transport):
    with ExitStack() as stack:
        console, hub = modbus_setup(stack, transport, tmp_path)
        decisions = []

        def tick_once():
            decisions.append(tick(hub, STATE, time.monotonic()))
        wait_for(lambda: decisions and decisions[-1].active["rudder"] == "io", poll=tick_once)
        console.stop()
        wait_for(lambda: any(d.controls.rudder == 0.0 for d in decisions), timeout=5.0, poll=tick_once)
        fail_safe = [d for d in decisions if d.controls.rudder == 0.0][0]
        assert fail_safe.controls.telegraph == "stop"  # midships and stop
        stale, failed = ALARM_NUMBERS["rudder"]
        assert {stale, failed, LINK_DOWN_ALARM} <= set(hub.active_alarms)
        console.set(0, 100)  # the console came back with a new order: 10 deg to starboard
        console.start()
        # back in use: how soon is the back-off's cap (test_links_base), not timed here
        wait_for(lambda: decisions[-1].controls.rudder is not None and decisions[-1].controls.rudder > 0,
                 timeout=10.0, poll=tick_once)
        assert decisions[-1].controls.rudder == pytest.approx(math.radians(10.0))
        assert not hub.active_alarms  # every alarm cleared
        assert hub.links[0].health().reconnects >= 1


def test_worker_errors_reach_health_only_through_the_loop():
    """The worker counts connect failures against a dead server; the loop reads consistent
    snapshots in a tight loop, and counts change only when the loop polls."""
    cfg = node_config([{"type": "modbus", "name": "io", "port": free_port(), "poll_hz": 100,
                        "registers": REGISTERS}], rudder=["io"])
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        link = hub.links[0]

        def poll_and_read() -> None:
            hub.poll(time.monotonic())
            for _ in range(200):
                hub.errors()
                link.health()
        wait_for(lambda: hub.errors()["connect_failed"] >= 3, poll=poll_and_read)
        before = hub.errors()
        wait_for(lambda: not link.device.events.empty())  # the worker has counted another failure
        assert hub.errors() == before  # not applied until the loop polls
        hub.poll(time.monotonic())
        assert hub.errors()["connect_failed"] > before["connect_failed"]
        assert not link.health().connected


def test_malformed_replies_are_failed_requests_and_the_link_recovers(tmp_path):
    """The HIL console's register server sends malformed MBAP headers (corrupt = "format"):
    each is a request that failed (counted, the connection reopened), never an order or a
    crash; the orders held are the last good ones, and good replies are in use again after."""
    port = free_port()
    settings = ModbusConsoleSettings(role="primary", type="modbus", port=port, registers=REGISTERS[:1])
    cfg = node_config([{"type": "modbus", "name": "io", "port": port, "registers": REGISTERS[:1], "poll_hz": 20}],
                      rudder=["io"])
    fault = Fault(at_s=0.0, kind="corrupt", corrupt="format", duration_s=600.0, probability=0.5)
    rudders = []
    with ConsoleModbus(settings) as console, LinkHub(cfg.links, cfg.arbitration, tmp_path / "rec") as hub:
        console.order(Order(OrderKind.RUDDER, math.radians(5.0)), time.monotonic())

        def tick_once() -> None:
            console.tick(time.monotonic())
            rudders.append(tick(hub, STATE, time.monotonic()).controls.rudder)
        wait_for(lambda: math.radians(5.0) in rudders, poll=tick_once)
        console.inject(fault, random.Random(7))
        wait_for(lambda: hub.errors()["request_failed"] >= 5, timeout=20.0, poll=tick_once)
        console.clear(fault)
        console.order(Order(OrderKind.RUDDER, math.radians(-3.0)), time.monotonic())
        wait_for(lambda: math.radians(-3.0) in rudders, timeout=10.0, poll=tick_once)
        health = hub.links[0].health()
    assert console.sent["bad_replies"] >= health.errors["request_failed"]
    assert set(health.errors) == {"request_failed"}  # no order from a bad reply, no worker died
    assert health.reconnects >= 1 and health.connected
    assert {r for r in rudders if r is not None} <= {math.radians(5.0), math.radians(-3.0), 0.0}  # 0: fail-safe
    reads = [row.split(",") for row in (tmp_path / "rec" / "modbus.csv").read_text().splitlines()[1:]]
    assert len(reads) == health.inputs  # every order the node took is in the session record, and only those
    assert {r[-1] for r in reads} == {"5.0", "-3.0"}
