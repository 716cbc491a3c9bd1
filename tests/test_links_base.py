"""The link family: the registry, ``Link.poll``'s reconnect and error accounting on an
explicit clock, context managers and double close, and the traffic listeners (the session
record's file formats pinned, since replay reads them)."""
import csv
import math
import re
import shutil
import time
from types import SimpleNamespace

import can
import pytest
from links_helpers import STATE, console_frame, node_config, tick

from bridge_node.links import session_record
from bridge_node.links.base import Link
from bridge_node.links.kind import LINK_KINDS
from bridge_node.links.device_io import Backoff
from bridge_node.links.messages import ControlInput, Listener, Traffic
from bridge_node.links.can.link import CONFIG_DIR, CanLink
from bridge_node.links.hub import LinkHub
from bridge_node.links.modbus.link import ModbusLink, RegisterAccess
from bridge_node.links.nmea0183.link import NmeaLink
from bridge_node.links.registry import make_link, open_link
from bridge_node.links.session_record import SessionRecord

LINKS = [{"type": "can", "name": "helm_can", "channel": "icebridge-base", "allowed_sources": "any"},
         {"type": "nmea0183", "name": "nmea", "udp_output": False},
         {"type": "modbus", "name": "io", "registers": [{"order": "rudder", "address": 0}]}]


def test_registry_builds_each_type_from_its_settings_alone():
    cfg = node_config(LINKS)
    assert set(LINK_KINDS) >= {"can", "nmea0183", "modbus", "dis"}
    links = [make_link(s) for s in cfg.links]
    assert [type(link) for link in links] == [CanLink, NmeaLink, ModbusLink]
    assert [link.name for link in links] == ["helm_can", "nmea", "io"]
    with pytest.raises(ValueError, match="carrier_pigeon"):
        make_link(SimpleNamespace(type="carrier_pigeon", name="x"))


def test_can_dbc_relative_to_the_config_folder_or_absolute(tmp_path):
    settings = node_config([LINKS[0]]).links[0]
    assert CanLink(settings).console.get_message_by_name("HelmOrder")  # "console.dbc" in config/
    renamed = tmp_path / "my_console.dbc"
    shutil.copy(CONFIG_DIR / "console.dbc", renamed)
    assert CanLink(settings.model_copy(update={"dbc": str(renamed)})).console.get_message_by_name("EngineOrder")
    with pytest.raises(FileNotFoundError):
        CanLink(settings.model_copy(update={"dbc": "my_console.dbc"}))  # not in config/


class FakeDevice:
    """A device whose next reads are scripted: orders, or an exception."""

    def __init__(self) -> None:
        self.script: list = []
        self.closed = 0

    def close(self) -> None:
        self.closed += 1


class FakeLink(Link):
    """A link over ``FakeDevice``; ``fail_opens`` failures before an open succeeds."""

    def __init__(self) -> None:
        super().__init__(SimpleNamespace(name="fake", engine=0))
        self.fail_opens = 0
        self.devices: list[FakeDevice] = []

    def _open_device(self) -> FakeDevice:
        if self.fail_opens:
            self.fail_opens -= 1
            raise OSError("no such device")
        self.devices.append(FakeDevice())
        return self.devices[-1]

    def _close_device(self, device: FakeDevice) -> None:
        device.close()

    def _poll_device(self, now: float):
        for item in self.device.script:
            if isinstance(item, Exception):
                raise item
            yield item
        self.device.script = []

    def publish(self, state, now: float) -> None:
        pass


def opened(link: Link) -> bool:
    """Wait (in the test, not the loop) for the link's opener to finish; whether it did."""
    return link._opener.wait(5.0)


def order(t: float) -> ControlInput:
    return ControlInput(t, "fake", "rudder", 0.1)


def test_poll_reopens_a_lost_device_after_the_back_off():
    link = FakeLink()
    link.open()
    assert link.health().connected
    link.device.script = [order(10.0), OSError("unplugged")]
    assert link.poll(10.0) == [order(10.0)]  # what came before the failure is kept
    h = link.health()
    assert not h.connected and h.errors == {"device_lost": 1} and h.inputs == 1
    assert link.devices[0].closed == 1 and link.device is None
    link.fail_opens = 1
    assert link.poll(10.05) == [] and link.health().reconnects == 0  # back-off: 0.1 s
    link.poll(10.1)  # reopen started on the opener's thread; the poll does not wait for it
    assert link.health().reconnects == 1 and link.health().opening
    assert opened(link) and link.health().errors["open_failed"] == 0
    link.poll(10.1)  # the next poll takes the failure: next back-off 0.2 s
    assert link.health().errors["open_failed"] == 1 and not link.health().opening
    link.poll(10.29)
    assert link.health().reconnects == 1
    link.poll(10.3)
    assert opened(link) and not link.health().connected
    link.poll(10.3)
    h = link.health()
    assert h.reconnects == 2 and h.connected and len(link.devices) == 2
    link.close()
    link.close()  # twice is safe
    assert link.devices[1].closed == 1 and not link.health().connected
    assert link.poll(20.0) == [] and link.health().reconnects == 2  # a closed link stays closed


def test_back_off_doubles_to_a_one_second_cap():
    b, now, waits = Backoff(), 0.0, []
    for _ in range(7):
        b.failed(now)
        waits.append(round(b.next_try - now, 6))
        now = b.next_try
    assert waits == [0.1, 0.2, 0.4, 0.8, 1.0, 1.0, 1.0]  # a peer back is in use within 1 s of the next try
    b.succeeded()
    assert b.ready(now) and b.delay == 0.1


def test_health_is_a_snapshot():
    link = FakeLink()
    link._count_error("bad")
    h = link.health()
    link._count_error("bad")
    assert h.errors == {"bad": 1} and link.health().errors == {"bad": 2}


def test_links_and_hub_are_context_managers_and_close_twice(tmp_path):
    settings = node_config([LINKS[0]]).links[0]
    with open_link(settings) as link:
        assert link.health().connected
    assert not link.health().connected and link.device is None
    link.close()
    cfg = node_config(LINKS[:2], rudder=["helm_can"])
    with LinkHub(cfg.links, cfg.arbitration, tmp_path / "rec") as hub:
        assert isinstance(hub.record, SessionRecord) and (tmp_path / "rec" / "nmea.log").exists()
        tick(hub, STATE, time.monotonic())
    hub.close()
    assert hub.record is None and not hub.listeners and all(not link.listeners for link in hub.links)


class Collect(Listener):
    def __init__(self) -> None:
        self.got: list[Traffic] = []
        self.flushes = self.stops = 0

    def on_traffic(self, traffic: Traffic) -> None:
        self.got.append(traffic)

    def flush(self) -> None:
        self.flushes += 1

    def stop(self) -> None:
        self.stops += 1


def test_hub_fans_traffic_out_to_listeners_and_the_record(tmp_path):
    cfg = node_config(LINKS[:2], rudder=["helm_can"])
    hub = LinkHub(cfg.links, cfg.arbitration, tmp_path)
    extra = Collect()
    hub.add_listener(extra)
    peer = can.Bus(interface="virtual", channel="icebridge-base")
    with hub:
        peer.send(console_frame("HelmOrder", RudderOrder=5.0, Status=1, Counter=1))
        d = tick(hub, STATE, time.monotonic())
    peer.shutdown()
    assert d.controls.rudder == pytest.approx(math.radians(5.0))
    assert extra.flushes == 1 and extra.stops == 1
    kinds = {(t.link, t.protocol, t.direction) for t in extra.got}
    assert kinds == {("helm_can", "can", "rx"), ("helm_can", "can", "tx"), ("nmea", "nmea0183", "tx")}
    frames = list(can.LogReader(str(tmp_path / "can.log")))
    assert [f.is_rx for f in frames].count(True) == 1 and len(frames) == sum(t.protocol == "can" for t in extra.got)
    lines = (tmp_path / "nmea.log").read_text().splitlines()
    assert lines and all(re.fullmatch(r"\d+\.\d{3} nmea tx \$[A-Z]{5},[^ ]*\*[0-9A-F]{2}", x) for x in lines)


def test_session_record_formats(tmp_path):
    rec = SessionRecord(tmp_path)
    rec.on_traffic(Traffic(1700000000.1234, "console", "nmea0183", "rx", "$RCROR,5.0,A,,V,B*5B\r\n"))
    rec.on_traffic(Traffic(1700000000.5, "io", "modbus", "read", RegisterAccess("holding", 0, 65381, -15.5)))
    rec.on_traffic(Traffic(1700000001.0, "io", "modbus", "write", RegisterAccess("holding", 10, 65413, math.nan)))
    msg = can.Message(timestamp=1700000002.25, arbitration_id=0x09F10D23, data=b"\x01\x02", is_extended_id=True)
    rec.on_traffic(Traffic(msg.timestamp, "helm", "can", "tx", msg))
    rec.stop()
    rec.stop()  # twice is safe
    assert (tmp_path / "nmea.log").read_text() == "1700000000.123 console rx $RCROR,5.0,A,,V,B*5B\n"
    assert list(csv.reader(open(tmp_path / "modbus.csv"))) == [
        ["unix_time", "link", "op", "table", "address", "raw", "value"],
        ["1700000000.500", "io", "read", "holding", "0", "65381", "-15.5"],
        ["1700000001.000", "io", "write", "holding", "10", "65413", "nan"]]
    (back,) = list(can.LogReader(str(tmp_path / "can.log")))
    assert back.timestamp == pytest.approx(1700000002.25) and back.arbitration_id == 0x09F10D23
    assert bytes(back.data) == b"\x01\x02"


def test_session_record_reaches_the_disk_within_the_flush_period(tmp_path, monkeypatch):
    """A killed node loses at most the lines of the last flush period (on a fake clock)."""
    clock = [100.0]
    monkeypatch.setattr(session_record, "time", SimpleNamespace(monotonic=lambda: clock[0], time=time.time))
    rec = SessionRecord(tmp_path)
    rec.on_traffic(Traffic(1700000000.0, "console", "nmea0183", "rx", "$RCROR,5.0,A,,V,B*5B"))
    clock[0] += session_record.FLUSH_PERIOD
    rec.flush()  # what a tick does
    assert (tmp_path / "nmea.log").read_text() == "1700000000.000 console rx $RCROR,5.0,A,,V,B*5B\n"
    rec.stop()
