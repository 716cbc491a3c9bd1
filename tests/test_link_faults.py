"""The instructor's faults on a named link, on a real NMEA 0183 link (pyserial's loop://
port, written as a console writes): orders dropped and corrupted (counted), duplicated,
delayed; a disconnect closes the device and raises the link-down alarm, and clearing it
reopens the link; the same fault at the same step draws the same orders."""
import math

from links_helpers import node_config

from bridge_node.links.faults import LinkFault
from bridge_node.links.hub import LinkHub
from bridge_node.links.nmea0183.link import NmeaLink
from bridge_node.links.nmea0183.sentences import checksum

ORDER = "RCROR,{:.1f},A,,V,B"


def _sentence(deg: float) -> bytes:
    body = ORDER.format(deg)
    return f"${body}*{checksum(body):02X}\r\n".encode()


def _hub() -> LinkHub:
    cfg = node_config([{"type": "nmea0183", "name": "helm", "port": "loop://", "udp_output": False}])
    return LinkHub(cfg.links, cfg.arbitration, made=[NmeaLink(cfg.links[0])])


def _orders(hub: LinkHub, degrees: list[float], now: float) -> list[float]:
    link = hub.links[0]
    for deg in degrees:
        link.device.port.write(_sentence(deg))
    return [round(math.degrees(o.value), 1) for o in link.poll(now)]


def test_drop_duplicate_delay_and_corrupt_act_on_the_orders_and_are_counted():
    with _hub() as hub:
        link = hub.links[0]
        assert _orders(hub, [1.0, 2.0], 1.0) == [1.0, 2.0]
        hub.fault_link(LinkFault("helm", "drop", 1.0, seed=7), 1.0)
        assert _orders(hub, [3.0, 4.0], 2.0) == []
        hub.fault_link(LinkFault("helm", "duplicate", 1.0, seed=8), 2.0)
        assert _orders(hub, [5.0], 3.0) == [5.0, 5.0]
        hub.fault_link(LinkFault("helm", "delay", 1.0, 0.5, seed=9), 3.0)
        assert _orders(hub, [6.0], 4.0) == []
        assert _orders(hub, [], 4.4) == []
        hub.fault_link(LinkFault("helm", "corrupt", 1.0, seed=10), 4.4)
        assert _orders(hub, [7.0], 4.6) == [6.0]  # the delayed order comes when due; the new one is refused
        hub.fault_link(LinkFault("helm", "none"), 4.6)
        assert _orders(hub, [8.0], 5.0) == [8.0]
        health = link.health()
        assert health.errors["fault_drop"] == 2 and health.errors["fault_corrupt"] == 1 and health.fault is None


def test_a_half_drop_draws_the_same_orders_for_the_same_seed():
    kept = []
    for _ in range(2):
        with _hub() as hub:
            hub.fault_link(LinkFault("helm", "drop", 0.5, seed=1234), 0.0)
            kept.append(_orders(hub, [float(k) for k in range(40)], 1.0))
    assert kept[0] == kept[1] and 5 < len(kept[0]) < 35


def test_a_disconnect_raises_the_link_down_alarm_and_clearing_it_reopens_the_link():
    with _hub() as hub:
        link = hub.links[0]
        assert hub.poll(1.0).alarms == []
        hub.fault_link(LinkFault("helm", "disconnect"), 1.0)
        [down] = hub.poll(1.1).alarms
        assert down.active and down.text == "link helm down: disconnected by the instructor"
        assert link.device is None and link.health().fault == "disconnect"
        assert hub.poll(5.0).alarms == [] and link.device is None  # not reopened while the fault lasts
        hub.fault_link(LinkFault("helm", "none"), 5.0)
        for k in range(100):
            link.poll(5.1 + 0.05 * k)
            if link.device is not None:
                break
            link.await_open(1.0)
        [up] = hub.poll(10.0).alarms
        assert not up.active and link.connected and _orders(hub, [9.0], 10.1) == [9.0]
