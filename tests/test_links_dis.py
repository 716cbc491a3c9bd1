"""DIS link on the loopback: the own ship's Entity State PDUs decoded by the independent
opendis package (its PDU parser and its own ECEF and Euler-angle conversions), sent at the
heartbeat and the dead-reckoning thresholds; PDUs that opendis builds, as another simulator
would send them, appear as AIS vessels on an NMEA link; bad PDUs are counted."""
import dataclasses
import datetime
import io
import math
import socket
import time
import zlib

import numpy as np
import pytest
from conftest import free_port, fuzz_budget
from hypothesis import given, settings
from hypothesis import strategies as st
from links_helpers import STATE, node_config, tick, wait_for
from opendis.DataOutputStream import DataOutputStream
from opendis.dis7 import EntityStatePdu
from opendis.PduFactory import createPdu
from opendis.RangeCoordinates import GPS
from pyais import decode
from pydantic import ValidationError

from bridge_node.links.nmea0183.ais import static_report
from sim_core.frames.geodesy import local_to_geodetic
from bridge_node.links.dis.link import DisLink, PduError
from bridge_node.links.hub import LinkHub
from bridge_node.links.dis.settings import DisLinkSettings
from sim_core.frames.units import KNOT


def receiver() -> socket.socket:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    s.settimeout(0.2)
    return s


def datagrams(s: socket.socket) -> list[bytes]:
    out = []
    try:
        while True:
            out.append(s.recv(4096))
    except socket.timeout:
        return out


def dis_link(send_to: socket.socket, **extra) -> dict:
    return {"type": "dis", "name": "dis", "listen_port": free_port(),
            "send_to": [f"127.0.0.1:{send_to.getsockname()[1]}"]} | extra


def test_own_ship_pdu_decodes_with_opendis_to_position_and_orientation():
    rx = receiver()
    cfg = node_config([dis_link(rx, site=7, application=8, entity=9, marking="POLARCARGO")])
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        tick(hub, STATE, time.monotonic())
    [data] = datagrams(rx)
    rx.close()
    pdu = createPdu(data)
    assert isinstance(pdu, EntityStatePdu) and len(data) == pdu.length == 144
    assert (pdu.protocolVersion, pdu.pduType, pdu.protocolFamily, pdu.exerciseID) == (7, 1, 1, 1)
    assert (pdu.entityID.siteID, pdu.entityID.applicationID, pdu.entityID.entityID) == (7, 8, 9)
    assert (pdu.entityType.entityKind, pdu.entityType.domain) == (1, 3)  # platform, surface
    assert pdu.marking.charactersString() == "POLARCARGO"
    loc, o = pdu.entityLocation, pdu.entityOrientation
    lat, lon, alt, roll, pitch, yaw = GPS().ecef2llarpy(loc.x, loc.y, loc.z, o.psi, o.theta, o.phi)
    assert lat == pytest.approx(STATE.latitude, abs=1e-8) and lon == pytest.approx(STATE.longitude, abs=1e-8)
    assert alt == pytest.approx(0.0, abs=0.01)
    assert yaw == pytest.approx(STATE.heading, abs=1e-5)  # float32 angles
    assert roll == pytest.approx(STATE.roll, abs=1e-5) and pitch == pytest.approx(STATE.pitch, abs=1e-5)
    north, east, down = GPS().ecefvec2nedvec(lat, lon)
    v = np.array([pdu.entityLinearVelocity.x, pdu.entityLinearVelocity.y, pdu.entityLinearVelocity.z])
    assert math.hypot(v @ north, v @ east) == pytest.approx(STATE.speed_over_ground, abs=1e-5)
    assert math.atan2(v @ east, v @ north) == pytest.approx(STATE.course_over_ground, abs=1e-5)
    assert v @ down == pytest.approx(0.0, abs=1e-5)
    dr = pdu.deadReckoningParameters
    assert dr.deadReckoningAlgorithm == 3 and dr.entityAngularVelocity.z == pytest.approx(STATE.rate_of_turn)


def test_pdus_at_the_heartbeat_and_the_dead_reckoning_thresholds():
    """On a simulated clock at 10 Hz: steady steaming sends only heartbeats (5 s); a 1.5 m
    jump, or a turn the last PDU did not announce, sends at once."""
    rx = receiver()
    cfg = node_config([dis_link(rx)])
    v = STATE.speed_over_ground
    cn, ce = v * math.cos(STATE.course_over_ground), v * math.sin(STATE.course_over_ground)

    def moved(north: float, east: float, **changes):  # the state (north, east) m on, its position with it
        lat, lon = local_to_geodetic(north, east, STATE.latitude, STATE.longitude)
        return dataclasses.replace(STATE, north=STATE.north + north, east=STATE.east + east, latitude=lat,
                                   longitude=lon, **changes)
    steady = [moved(cn * 0.1 * k, ce * 0.1 * k, heading=STATE.heading + STATE.rate_of_turn * 0.1 * k)
              for k in range(201)]
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        t0 = time.monotonic()
        for k, state in enumerate(steady):
            tick(hub, state, t0 + 0.1 * k)
        heartbeats = len(datagrams(rx))
        last = steady[-1]
        tick(hub, moved(cn * 20.0, ce * 20.0 + 1.5, heading=last.heading), t0 + 20.1)  # 1.5 m off the dead reckoning
        jump = len(datagrams(rx))
        tick(hub, dataclasses.replace(last, heading=last.heading + math.radians(3.5)), t0 + 20.2)
        turn = len(datagrams(rx))
        tick(hub, dataclasses.replace(last, heading=last.heading + math.radians(3.5)), t0 + 20.3)
    rx.close()
    assert heartbeats == 5  # at 0, 5, 10, 15 and 20 s
    assert (jump, turn) == (1, 1)


def other_simulator_pdu(lat_deg: float, lon_deg: float, heading: float, speed: float, site: int = 3,
                        domain: int = 3, exercise: int = 1, marking: str = "ODEN") -> bytes:
    """An Entity State PDU as another simulator sends it, built by opendis alone."""
    pdu = EntityStatePdu()
    pdu.exerciseID, pdu.pduStatus, pdu.length = exercise, 0, 144
    pdu.pduType, pdu.protocolFamily = 1, 1  # opendis 1.0 leaves both 0
    pdu.entityAppearance = pdu.capabilities = 0  # opendis 1.0 defaults these to bytes it cannot write
    pdu.entityID.siteID, pdu.entityID.applicationID, pdu.entityID.entityID = site, 1, 42
    pdu.entityType.entityKind, pdu.entityType.domain = 1, domain
    gps = GPS()
    x, y, z, psi, theta, phi = gps.llarpy2ecef(math.radians(lat_deg), math.radians(lon_deg), 0.0, 0.0, 0.0, heading)
    pdu.entityLocation.x, pdu.entityLocation.y, pdu.entityLocation.z = x, y, z
    pdu.entityOrientation.psi, pdu.entityOrientation.theta, pdu.entityOrientation.phi = psi, theta, phi
    north, east, _ = gps.ecefvec2nedvec(math.radians(lat_deg), math.radians(lon_deg))
    vx, vy, vz = speed * (math.cos(heading) * np.asarray(north) + math.sin(heading) * np.asarray(east))
    pdu.entityLinearVelocity.x, pdu.entityLinearVelocity.y, pdu.entityLinearVelocity.z = vx, vy, vz
    pdu.deadReckoningParameters.deadReckoningAlgorithm = 2
    pdu.marking.setString(marking)
    buf = io.BytesIO()
    pdu.serialize(DataOutputStream(buf))
    return buf.getvalue()


def dis_and_plotter(listen: int, nmea_rx: socket.socket):
    """A DIS link listening on ``listen`` and a plotter's NMEA link sending only AIS to ``nmea_rx``."""
    return node_config([
        {"type": "dis", "name": "dis", "listen_port": listen, "send_to": [f"127.0.0.1:{free_port()}"]},
        {"type": "nmea0183", "name": "plotter", "udp_port": nmea_rx.getsockname()[1],
         "rates": {k: 0 for k in ("RMC", "GGA", "VTG", "ZDA", "HDT", "ROT", "RSA", "RPM", "VBW", "XDR")},
         "ais": {"mmsi": 257123450, "to_bow": 20, "to_stern": 130, "to_port": 10, "to_starboard": 12}}])


def test_a_vessel_from_another_simulator_goes_out_as_ais(tmp_path):
    nmea_rx, listen = receiver(), free_port()
    cfg = dis_and_plotter(listen, nmea_rx)
    sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        sim.sendto(other_simulator_pdu(74.02, 20.03, math.radians(250.0), 6.0), ("127.0.0.1", listen))
        t0 = time.monotonic()
        for k in range(5):
            tick(hub, STATE, t0 + 0.01 * k)
        [vessel] = hub.links[0].vessels(t0 + 0.04)
        gone = hub.links[0].vessels(t0 + 12.5)  # 12 s without a PDU: gone
    sim.close()
    sentences = [d.decode().strip() for d in datagrams(nmea_rx)]
    nmea_rx.close()
    vdm = [s for s in sentences if s.startswith("!AIVDM")]
    report = decode(vdm[0]).asdict()
    static = decode(*vdm[1:3]).asdict()
    assert report["msg_type"] == 1 and static["msg_type"] == 5
    assert report["mmsi"] == static["mmsi"] == 200_000_000 + zlib.crc32(b"dis:3.1.42") % 1_000_000
    assert report["lat"] == pytest.approx(74.02, abs=2e-4 / 60) and report["lon"] == pytest.approx(20.03, abs=2e-4 / 60)
    assert report["heading"] == 250 and report["speed"] == pytest.approx(6.0 / KNOT, abs=0.05)
    assert report["course"] == pytest.approx(250.0, abs=0.1)
    assert static["shipname"] == "ODEN"
    assert vessel.name == "ODEN" and gone == []
    assert any(s.startswith("!AIVDO") for s in sentences)  # the own ship too


def test_a_marking_outside_ais_text_is_sanitised_counted_and_the_traffic_goes_on():
    """One PDU whose marking holds characters AIS 6-bit text lacks used to raise KeyError in
    pyais inside the hub's publish, which stopped ``icebridge run``."""
    nmea_rx, listen = receiver(), free_port()
    cfg = dis_and_plotter(listen, nmea_rx)
    sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        sim.sendto(other_simulator_pdu(74.02, 20.03, 0.0, 3.0, marking="od{|}~`en"), ("127.0.0.1", listen))
        link = hub.links[0]
        wait_for(lambda: link.vessels(time.monotonic()), poll=lambda: tick(hub, STATE, time.monotonic()))
        for _ in range(3):
            tick(hub, STATE, time.monotonic())
        errors = dict(link.health().errors)
    sim.close()
    vdm = [d.decode().strip() for d in datagrams(nmea_rx) if d.startswith(b"!AIVDM")]
    nmea_rx.close()
    static = decode(*vdm[1:3]).asdict()
    assert static["shipname"] == "OD     EN"
    assert errors == {"marking_sanitised": 1}


def test_bad_and_foreign_pdus_are_counted_own_echoes_skipped():
    listen = free_port()
    cfg = node_config([{"type": "dis", "name": "dis", "listen_port": listen, "send_to": [f"127.0.0.1:{listen}"]}])
    good = other_simulator_pdu(74.0, 20.0, 0.0, 0.0)
    nan = bytearray(good)
    nan[48:56] = np.float64("nan").byteswap().tobytes()  # location x
    sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    with LinkHub(cfg.links, cfg.arbitration) as hub:
        tick(hub, STATE, time.monotonic())  # the node's own PDU comes back to it: skipped
        for pdu in (b"\x07\x01", good[:100], other_simulator_pdu(74.0, 20.0, 0.0, 0.0, exercise=2),
                    other_simulator_pdu(74.0, 20.0, 0.0, 0.0, domain=2), bytes(nan), good):
            sim.sendto(pdu, ("127.0.0.1", listen))
        link = hub.links[0]
        wait_for(lambda: sum(link.health().errors.values()) == 5 and link.vessels(time.monotonic()),
                 poll=lambda: tick(hub, STATE, time.monotonic()))
        vessels = link.vessels(time.monotonic())
    sim.close()
    assert dict(hub.links[0].health().errors) == {"malformed": 2, "ignored": 2, "bad_field": 1}
    assert [v.key for v in vessels] == ["dis:3.1.42"]


def test_dis_goes_off_the_host_only_when_allowed():
    with pytest.raises(ValidationError, match="send_to"):
        node_config([{"type": "dis", "name": "dis", "send_to": ["192.168.1.20:3000"]}])
    node_config([{"type": "dis", "name": "dis", "send_to": ["192.168.1.20:3000"], "allow_network": True}])


@settings(max_examples=fuzz_budget(2000), deadline=None)
@given(st.binary(max_size=200), st.integers(0, 143), st.integers(0, 255))
def test_any_datagram_is_a_vessel_or_a_counted_kind(data, where, value):
    """Random datagrams, and real PDUs with one byte changed, never crash the parser."""
    link = DisLink(DisLinkSettings(type="dis", name="fuzz"))
    corrupted = bytearray(GOOD)
    corrupted[where] = value
    for pdu in (data, bytes(corrupted)):
        try:
            entity = link.heard.entity(pdu, 0.0)
        except PduError as exc:
            assert exc.kind in ("malformed", "ignored", "bad_field")
            continue
        if entity is not None:
            v = entity.at(1.0)
            assert all(math.isfinite(x) for x in (v.latitude, v.longitude, v.heading))
            assert v.speed_over_ground <= 100.0
            assert static_report(v.mmsi, v.name, (1, 1, 1, 1), UTC, "VDM", 0)  # AIS can send what DIS took


GOOD = other_simulator_pdu(74.0, 20.0, 1.0, 5.0)
UTC = datetime.datetime(2026, 3, 1, tzinfo=datetime.timezone.utc)
