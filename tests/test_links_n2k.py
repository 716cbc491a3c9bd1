"""NMEA 2000 citizenship on python-can's virtual bus and over slcan on a pty pair: address
claim, ISO request answers, heartbeat, conflicts won and lost, and every PGN's priority;
decoded by the independent nmea2000 package (canboat's database), with nmea2000's own
ISO 11783-5 address claimer as a second device on the bus."""
import time

import can
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from links_helpers import STATE, node_config, pty_pair, tick, wait_for
from nmea2000._canboat import AddressClaimer, iso_name
from nmea2000.decoder import NMEA2000Decoder

from bridge_node.links.can.link import CanLink
from bridge_node.links.hub import LINK_DOWN_ALARM, LinkHub
from bridge_node.links.can.n2k_frames import identifier
from bridge_node.links.can.n2k_network import N2kName
from bridge_node.links.can.settings import CanLinkSettings

# canboat's database (github canboat/canboat docs/canboat.json, commit 01d0dc3, 2026-08-16):
# "Priority" of every PGN the node sends
CANBOAT_PRIORITY = {127245: 2, 127488: 2, 127489: 2, 127250: 2, 127251: 2, 127257: 3, 129025: 2, 129026: 2, 60928: 6,
                    59392: 6, 126996: 6, 126464: 6, 126993: 7}
NODE_NAME = {"identity_number": 4242, "manufacturer_code": 2046, "device_function": 170, "device_class": 60}


def peer_name(identity: int, device_class: int, arbitrary: bool = True) -> int:
    """A NAME composed by nmea2000 (not by the node's code): lower class, lower NAME (the
    arbitrary-address bit is the highest)."""
    return iso_name(2046, identity, device_function=130, device_class=device_class, device_instance=0,
                    system_instance=0, industry_group=4, arbitrary_address_capable=arbitrary)


def claim(source: int, name: int) -> can.Message:
    return can.Message(arbitration_id=identifier(6, 60928, source), data=name.to_bytes(8, "little"),
                       is_extended_id=True)


def iso_request(pgn: int, source: int = 0x10, destination: int = 0xFF) -> can.Message:
    return can.Message(arbitration_id=identifier(6, 59904, source, destination), data=pgn.to_bytes(3, "little"),
                       is_extended_id=True)


def decoded(bus: can.BusABC, decoder: NMEA2000Decoder, timeout: float = 0.05) -> list:
    """Every complete PGN on the bus until it is quiet: (pgn, source, destination, priority, fields)."""
    out = []
    while (msg := bus.recv(timeout=timeout)) is not None:
        m = decoder.decode(msg)
        if m is not None:
            out.append((m.PGN, m.source, m.destination, m.priority, {f.id: f.value for f in m.fields}))
    return out


def can_settings(channel: str, interface: str = "virtual", **extra) -> dict:
    return {"type": "can", "name": "n2k", "interface": interface, "channel": channel, "allowed_sources": "any",
            "n2k_name": NODE_NAME, "heartbeat_s": 1.0} | extra


@pytest.fixture
def bus_pair(request):
    channel = f"icebridge-n2k-{request.node.name}"
    cfg = node_config([can_settings(channel)])
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        peer = can.Bus(interface="virtual", channel=channel)
        yield hub, peer
        peer.shutdown()


def test_claim_at_start_and_answers_to_iso_requests(bus_pair):
    hub, peer = bus_pair
    dec, t0 = NMEA2000Decoder(), time.monotonic()
    tick(hub, STATE, t0)
    first = decoded(peer, dec)
    assert first[0][:4] == (60928, 0x23, 255, 6)  # the claim comes first, then the outputs
    name = first[0][4]
    assert (name["uniqueNumber"], name["deviceFunction"], name["deviceClass"], name["industryGroup"],
            name["arbitraryAddressCapable"]) == (4242, "Integrated Navigation", "Navigation", "Marine Industry", "Yes")
    for pgn in (60928, 126996, 126464, 126993, 130306):
        peer.send(iso_request(pgn))
    peer.send(iso_request(130306, destination=0x23))  # a PGN the node does not send, asked of it: refused
    peer.send(iso_request(126996, destination=0x30))  # asked of another device: not answered
    tick(hub, STATE, t0 + 0.3)
    by_pgn = {}
    for m in decoded(peer, dec):
        by_pgn.setdefault(m[0], []).append(m)
    assert len(by_pgn[60928]) == 1 and len(by_pgn[126996]) == 1 and len(by_pgn[59392]) == 1
    assert len(by_pgn[126993]) == 2  # the first periodic heartbeat, and the answer
    info = by_pgn[126996][0][4]
    assert info["nmea2000Version"] == pytest.approx(2.1) and info["modelId"] == "IceBridge simulator node"
    assert info["softwareVersionCode"].startswith("IceBridge")
    lists = {m[4]["functionCode"]: {e["pgn"].value for e in m[4]["##list##"]} for m in by_pgn[126464]}
    assert {127245, 127489, 129026, 60928, 126993, 126996} <= lists["Transmit PGN list"]
    assert {59904, 60928, 127245, 0xFF50, 0xFF51} <= lists["Receive PGN list"]
    nak = by_pgn[59392][0]
    assert nak[2] == 0x10 and nak[4]["control"] == "NAK" and nak[4]["pgn"] == 130306


def test_heartbeat_at_its_period(bus_pair):
    hub, peer = bus_pair
    t0 = time.monotonic()
    for k in range(36):  # 3.5 s on a simulated clock; the claim is held from t0 + 0.25 s
        tick(hub, STATE, t0 + 0.1 * k)
    beats = [m for m in decoded(peer, NMEA2000Decoder()) if m[0] == 126993]
    assert [m[4]["sequenceCounter"] for m in beats] == [1, 2, 3, 4]  # at 0.3, 1.3, 2.3 and 3.3 s
    assert all(m[3] == 7 and m[4]["dataTransmitOffset"] == pytest.approx(1.0) for m in beats)
    assert {m[4]["equipmentStatus"] for m in beats} == {"Operational"}


def test_every_pgn_at_the_priority_of_canboats_database(bus_pair):
    hub, peer = bus_pair
    t0 = time.monotonic()
    for pgn in (126996, 126464):
        peer.send(iso_request(pgn))
    peer.send(iso_request(130306, destination=0x23))
    for k in range(12):
        tick(hub, STATE, t0 + 0.1 * k)
    seen = {m[0]: m[3] for m in decoded(peer, NMEA2000Decoder())}
    assert seen == CANBOAT_PRIORITY


def test_conflicts_won_are_defended_and_lost_ones_move_to_a_free_address(bus_pair):
    hub, peer = bus_pair
    dec, t0 = NMEA2000Decoder(), time.monotonic()
    tick(hub, STATE, t0)
    tick(hub, STATE, t0 + 0.3)
    decoded(peer, dec)
    higher, lower = peer_name(7, 120), peer_name(7, 10)  # a display (class 120) and a system tool (class 10)
    assert higher > N2kName(**NODE_NAME).value() > lower
    peer.send(claim(0x23, higher))  # the node's NAME is lower: it keeps 0x23 and claims it again
    tick(hub, STATE, t0 + 0.4)
    assert [m[:2] for m in decoded(peer, dec) if m[0] == 60928] == [(60928, 0x23)]
    peer.send(claim(0x24, peer_name(8, 120)))  # 0x24 is taken by a third device
    peer.send(claim(0x23, lower))  # the node loses 0x23: it claims the next free address, 0x25
    tick(hub, STATE, t0 + 0.5)
    tick(hub, STATE, t0 + 0.9)
    after = decoded(peer, dec)
    assert [m[:2] for m in after if m[0] == 60928] == [(60928, 0x25)]
    assert {m[1] for m in after if m[0] == 127250} == {0x25}  # its outputs follow it
    assert not hub.active_alarms


def test_an_independent_claimer_sees_the_nodes_address_taken(bus_pair):
    """nmea2000's address claimer asks who is there before claiming: the node answers, and
    the other device chooses another address."""
    hub, peer = bus_pair
    t0 = time.monotonic()
    tick(hub, STATE, t0)
    other = AddressClaimer(peer_name(9, 120), 0x23, True)
    for frame in other.start(0):
        peer.send(can.Message(arbitration_id=identifier(frame[0], frame[1], frame[2], frame[3]), data=frame[4],
                              is_extended_id=True))
    tick(hub, STATE, t0 + 0.3)
    claims = 0
    while (msg := peer.recv(timeout=0.05)) is not None:  # the node's claims as they are on the wire
        if (msg.arbitration_id >> 8) & 0x3FF00 == 60928:
            claims += 1
            other.on_address_claim(10, msg.arbitration_id & 0xFF, int.from_bytes(msg.data, "little"))
    assert claims == 2  # at start, and the answer to the other device's request
    other.tick(1000)
    other.tick(1300)
    assert other.state == "claimed" and other.address not in (None, 0x23)


def test_a_node_that_cannot_claim_goes_silent_and_says_so(request):
    channel = f"icebridge-n2k-{request.node.name}"
    cfg = node_config([can_settings(channel, n2k_name=NODE_NAME | {"arbitrary_address_capable": False})])
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        peer = can.Bus(interface="virtual", channel=channel)
        dec, t0 = NMEA2000Decoder(), time.monotonic()
        tick(hub, STATE, t0)
        decoded(peer, dec)
        peer.send(claim(0x23, peer_name(7, 10, arbitrary=False)))
        for k in range(1, 6):
            tick(hub, STATE, t0 + 0.1 * k)
        after = decoded(peer, dec)
        peer.send(iso_request(60928))
        tick(hub, STATE, t0 + 0.7)
        answer = decoded(peer, dec)
        peer.shutdown()
    assert [m[:2] for m in after] == [(60928, 254)]  # cannot claim, from the null address; then silence
    assert after[0][4]["uniqueNumber"] == 4242
    assert [m[:2] for m in answer] == [(60928, 254)]  # asked, it says so again
    assert hub.links[0].health().errors["cannot_claim"] == 1
    assert LINK_DOWN_ALARM in {a.number for _, a in hub.alarm_log}


def test_claim_requests_and_a_lost_conflict_over_slcan(tmp_path):
    """The node on slcan, as with a USB-CAN adapter; the other devices on the pty's far end."""
    with pty_pair(tmp_path) as (node_end, far_end):
        cfg = node_config([can_settings(node_end, interface="slcan")])
        hub = LinkHub(cfg.links, cfg.arbitration)
        hub.open()
        peer = can.Bus(interface="slcan", channel=far_end, bitrate=250000)
        dec = NMEA2000Decoder()
        got = []
        try:
            wait_for(lambda: any(m[0] == 60928 for m in got),
                     poll=lambda: (tick(hub, STATE, time.monotonic()), got.extend(decoded(peer, dec, 0.01))))
            peer.send(iso_request(126996))
            wait_for(lambda: any(m[0] == 126996 for m in got),
                     poll=lambda: (tick(hub, STATE, time.monotonic()), got.extend(decoded(peer, dec, 0.01))))
            peer.send(claim(0x23, peer_name(7, 10)))
            wait_for(lambda: any(m[:2] == (60928, 0x24) for m in got),
                     poll=lambda: (tick(hub, STATE, time.monotonic()), got.extend(decoded(peer, dec, 0.01))))
            wait_for(lambda: any(m[:2] == (127250, 0x24) for m in got),
                     poll=lambda: (tick(hub, STATE, time.monotonic()), got.extend(decoded(peer, dec, 0.01))))
        finally:
            peer.shutdown()
            hub.close()
    assert [m[4]["modelId"] for m in got if m[0] == 126996] == ["IceBridge simulator node"]
    assert got[0][:4] == (60928, 0x23, 255, 6)


@settings(max_examples=500, deadline=None)
@given(st.sampled_from([(59904, 0xFF), (59904, 0x23), (60928, 0xFF)]), st.integers(0, 253), st.binary(max_size=8))
def test_network_frames_with_any_payload_are_answered_or_counted(pgn_destination, source, data):
    pgn, destination = pgn_destination
    link = CanLink(CanLinkSettings(type="can", name="fuzz", channel="icebridge-fuzz-n2k", allowed_sources="any"))
    link.network.tick(0.0)
    out = link._decode(can.Message(arbitration_id=identifier(6, pgn, source, destination), data=data,
                                   is_extended_id=True), 0.0)
    assert out == []
    assert sum(link.health().errors.values()) == (len(data) != 8 if pgn == 60928 else len(data) < 3)
