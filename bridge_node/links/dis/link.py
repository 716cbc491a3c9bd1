"""DIS link (IEEE 1278.1-2012, DIS 7): the own ship as Entity State PDUs, unicast over UDP
to the configured hosts (loopback by default; no multicast, no broadcast), and the Entity
State PDUs of other simulators as other vessels, which the hub hands to every link (the
NMEA links send them as AIS targets).

- **Sending**: a PDU when the heartbeat (5 s) has passed, or when the dead reckoning the
  receivers do from the last PDU (algorithm 3, rotating with constant velocity in world
  coordinates) has drifted more than 1 m in position or 3 deg in heading.
- **Frames**: location and velocity are geocentric (WGS 84 ECEF, m and m/s), orientation
  the Tait-Bryan angles psi, theta, phi from the ECEF axes to the ship's body (x forward,
  y starboard, z down); the angular velocity is the body's (the yaw rate about z).
- **Receiving**: PDUs of the same exercise, entity kind platform, domain surface or
  subsurface, become vessels, dead-reckoned to the time they are read and forgotten after
  ``vessel_timeout_s`` (12 s: 2.4 heartbeats, the standard's default). Each gets an MMSI
  from ``mmsi_base`` (200 000 000: no country's MID) and its entity id. The node's own
  PDUs, looped back, are skipped; other PDU types, exercises and entities are ``ignored``;
  a PDU that is short or whose length field is wrong is ``malformed``; non-finite or
  off-Earth positions and speeds over 100 m/s are ``bad_field``. A marking with characters
  that AIS 6-bit text lacks is kept with them as spaces and counted ``marking_sanitised``.

PDUs are packed and unpacked with ``struct`` (144 bytes, big-endian, no variable
parameters); the tests decode and encode them with the independent opendis package.
"""
from __future__ import annotations

import math
import socket
import struct
import time
import zlib
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from bridge_node.links.nmea0183.ais import six_bit_text
from bridge_node.links.base import Link
from bridge_node.links.messages import ControlInput, Vessel
from bridge_node.links.dis.settings import DisLinkSettings
from sim_core.ship.outputs import ShipOutputs

PROTOCOL_VERSION, ENTITY_STATE, ENTITY_INFORMATION_FAMILY = 7, 1, 1
PLATFORM, SURFACE, SUBSURFACE = 1, 3, 4
DR_RPW = 3  # dead reckoning: rotating, constant velocity, world coordinates
ESPDU = struct.Struct(">BBBBIHBB HHH BB BBHBBBB BBHBBBB 3f 3d 3f I B15s 3f 3f B11s I")  # 144 bytes
MAX_PDUS_PER_POLL = 1000
WGS84_A, WGS84_E2 = 6378137.0, 6.69437999014e-3
EARTH_SHELL_M = (6.30e6, 6.45e6)  # |ECEF location| of a vessel lies within this
MAX_SPEED_MPS = 100.0  # no vessel is faster: a PDU saying so is bad


def ned_to_ecef(lat: float, lon: float) -> np.ndarray:
    """Rotation whose columns are north, east and down at (lat, lon) in ECEF axes."""
    sl, cl, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    return np.array([[-sl * co, -so, -cl * co], [-sl * so, co, -cl * so], [cl, 0.0, -sl]])


def geodetic_to_ecef(lat: float, lon: float, height: float = 0.0) -> np.ndarray:
    """WGS 84 geocentric position, m; lat/lon rad."""
    n = WGS84_A / math.sqrt(1.0 - WGS84_E2 * math.sin(lat) ** 2)
    return np.array([(n + height) * math.cos(lat) * math.cos(lon), (n + height) * math.cos(lat) * math.sin(lon),
                     (n * (1.0 - WGS84_E2) + height) * math.sin(lat)])


def ecef_to_geodetic(xyz: np.ndarray) -> tuple[float, float]:
    """Latitude and longitude (rad) of a geocentric position near the Earth's surface."""
    x, y, z = xyz
    p = math.hypot(x, y)
    lat = math.atan2(z, p * (1.0 - WGS84_E2))
    for _ in range(5):  # converges to well under a millimetre near the surface
        n = WGS84_A / math.sqrt(1.0 - WGS84_E2 * math.sin(lat) ** 2)
        lat = math.atan2(z + WGS84_E2 * n * math.sin(lat), p)
    return lat, math.atan2(y, x)


def euler_from_matrix(r: np.ndarray) -> tuple[float, float, float]:
    """DIS psi, theta, phi (z-y-x) of a body-to-ECEF rotation."""
    return math.atan2(r[1, 0], r[0, 0]), -math.asin(max(-1.0, min(1.0, r[2, 0]))), math.atan2(r[2, 1], r[2, 2])


def matrix_from_euler(psi: float, theta: float, phi: float) -> np.ndarray:
    """The body-to-ECEF rotation of DIS psi, theta, phi."""
    cps, sps, cth, sth, cph, sph = (math.cos(psi), math.sin(psi), math.cos(theta), math.sin(theta), math.cos(phi),
                                    math.sin(phi))
    rz = np.array([[cps, -sps, 0.0], [sps, cps, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cth, 0.0, sth], [0.0, 1.0, 0.0], [-sth, 0.0, cth]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cph, -sph], [0.0, sph, cph]])
    return rz @ ry @ rx


def dis_timestamp(unix_time: float) -> int:
    """Absolute DIS timestamp: units of 3600 / 2**31 s past the hour, lowest bit 1."""
    return (int((unix_time % 3600.0) / 3600.0 * 2**31) << 1 | 1) & 0xFFFFFFFF


def entity_state_pdu(s: DisLinkSettings, state: ShipOutputs, unix_time: float) -> bytes:
    """The own ship's Entity State PDU."""
    to_ecef = ned_to_ecef(state.latitude, state.longitude)
    body = to_ecef @ matrix_from_euler(state.heading, state.pitch, state.roll)  # body (x fwd, y stbd, z down) to NED
    velocity = to_ecef @ np.array([state.speed_over_ground * math.cos(state.course_over_ground),
                                   state.speed_over_ground * math.sin(state.course_over_ground), 0.0])
    location = geodetic_to_ecef(state.latitude, state.longitude)
    entity_type = (PLATFORM, SURFACE, s.country, s.category, s.subcategory, 0, 0)
    return ESPDU.pack(PROTOCOL_VERSION, s.exercise_id, ENTITY_STATE, ENTITY_INFORMATION_FAMILY,
                      dis_timestamp(unix_time), ESPDU.size, 0, 0, s.site, s.application, s.entity, s.force_id, 0,
                      *entity_type, *entity_type, *velocity, *location, *euler_from_matrix(body), 0, DR_RPW,
                      b"\x00" * 15, 0.0, 0.0, 0.0, 0.0, 0.0, state.rate_of_turn, 1,
                      s.marking.encode("ascii").ljust(11, b"\x00"), 0)


@dataclass(frozen=True)
class _Entity:
    """What a received PDU said, for dead reckoning: ECEF location and velocity at ``time``."""

    key: str
    mmsi: int
    name: str  # AIS 6-bit text
    marking: str  # as received (latin-1), or the key where it was empty
    time: float  # monotonic s when read
    location: np.ndarray
    velocity: np.ndarray
    heading: float
    rate_of_turn: float

    def at(self, now: float) -> Vessel:
        """The vessel dead-reckoned to ``now`` (constant velocity and yaw rate)."""
        dt = now - self.time
        lat, lon = ecef_to_geodetic(self.location + self.velocity * dt)
        north, east, _ = ned_to_ecef(lat, lon).T @ self.velocity
        return Vessel(self.key, self.mmsi, self.name, self.time, lat, lon,
                      (self.heading + self.rate_of_turn * dt) % (2 * math.pi), math.atan2(east, north) % (2 * math.pi),
                      math.hypot(north, east), self.rate_of_turn)


class PduError(ValueError):
    """A PDU that is not a vessel; ``kind`` names it for the counters."""

    def __init__(self, kind: str) -> None:
        super().__init__(kind)
        self.kind = kind


class HeardEntities:
    """Other simulators' entities as their Entity State PDUs describe them, for the exercise,
    own entity and MMSIs of ``settings``: dead-reckoned vessels until ``vessel_timeout_s``
    of silence. The DIS link feeds it what it reads; a replay, what a session recorded."""

    def __init__(self, settings: DisLinkSettings) -> None:
        self.settings = settings
        self._own = (settings.site, settings.application, settings.entity)
        self._entities: dict[str, _Entity] = {}

    def hear(self, data: bytes, now: float) -> str | None:
        """Take one PDU read at ``now`` (monotonic s); PduError for one that is no vessel.
        Returns ``"marking_sanitised"`` where the entity's marking held characters that AIS
        6-bit text lacks (they became spaces; the vessel is kept), else None."""
        entity = self.entity(data, now)
        if entity is None:
            return None
        self._entities[entity.key] = entity
        return "marking_sanitised" if entity.name != entity.marking else None

    def entity(self, data: bytes, now: float) -> _Entity | None:
        """The vessel a PDU describes; None for the node's own; PduError for the rest."""
        if len(data) < 12:
            raise PduError("malformed")
        _, exercise, pdu_type, _, _, length = struct.unpack_from(">BBBBIH", data)
        if exercise != self.settings.exercise_id or pdu_type != ENTITY_STATE:
            raise PduError("ignored")
        if len(data) < ESPDU.size or length != len(data):
            raise PduError("malformed")
        f = ESPDU.unpack_from(data)
        site_app_entity, kind, domain = f[8:11], f[13], f[14]
        if site_app_entity == self._own:
            return None
        if kind != PLATFORM or domain not in (SURFACE, SUBSURFACE):
            raise PduError("ignored")
        velocity, location, (psi, theta, phi) = np.array(f[27:30]), np.array(f[30:33]), f[33:36]
        rate = f[44]  # angular velocity about the body's z (down): yaw rate, + to starboard
        values = (*velocity, *location, psi, theta, phi, rate)
        if not all(math.isfinite(v) for v in values) or float(np.linalg.norm(velocity)) > MAX_SPEED_MPS or \
                not EARTH_SHELL_M[0] < float(np.linalg.norm(location)) < EARTH_SHELL_M[1]:
            raise PduError("bad_field")
        lat, lon = ecef_to_geodetic(location)
        north, east, _ = ned_to_ecef(lat, lon).T @ matrix_from_euler(psi, theta, phi)[:, 0]
        key = "dis:{}.{}.{}".format(*site_app_entity)
        # character set 1 is ASCII; some senders leave it 0 (unused). The name goes out as AIS
        # 6-bit text, so it is made so here, at the boundary: any simulator on the DIS network
        # may send any bytes (one marking of "{|}~" used to stop the node's AIS encoding).
        marking = f[46].split(b"\x00")[0].decode("latin-1")
        name = six_bit_text(marking) or six_bit_text(key)
        return _Entity(key, self.settings.mmsi_base + zlib.crc32(key.encode()) % 1_000_000, name, marking or key,
                       now, location, velocity, math.atan2(east, north) % (2 * math.pi), rate)

    def vessels(self, now: float) -> list[Vessel]:
        """The vessels heard within the timeout, dead-reckoned to ``now`` (monotonic s)."""
        timeout = self.settings.vessel_timeout_s
        self._entities = {k: e for k, e in self._entities.items() if now - e.time <= timeout}
        return [e.at(now) for e in self._entities.values()]


class DisLink(Link):
    """Own ship out as Entity State PDUs (where it is, whatever its sensors read), other
    simulators' entities in as vessels."""

    lost_kind = "socket_lost"
    simulator_peer = True

    def __init__(self, settings: DisLinkSettings) -> None:
        super().__init__(settings)
        self.heard = HeardEntities(settings)
        self._sent = None  # (now, north, east, north speed, east speed, heading, rate of turn) of the last PDU

    def _open_device(self) -> socket.socket:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.bind((self.settings.listen_host, self.settings.listen_port))
        except OSError:
            sock.close()
            raise
        sock.setblocking(False)
        return sock

    def _close_device(self, sock: socket.socket) -> None:
        sock.close()

    def _poll_device(self, now: float) -> Iterator[ControlInput]:
        for _ in range(MAX_PDUS_PER_POLL):
            try:
                data = self.device.recv(2048)
            except BlockingIOError:
                break
            self._report("rx", data)
            try:
                note = self.heard.hear(data, now)
            except PduError as exc:
                self._count_error(exc.kind)
            else:
                if note is not None:
                    self._count_error(note)
        return iter(())

    def vessels(self, now: float) -> list[Vessel]:
        return self.heard.vessels(now)

    def _due(self, state: ShipOutputs, now: float) -> bool:
        """Heartbeat passed, or the receivers' dead reckoning drifted past a threshold."""
        if self._sent is None:
            return True
        t, north, east, vn, ve, heading, rate = self._sent
        dt = now - t
        drift = math.hypot(state.north - north - vn * dt, state.east - east - ve * dt)
        turn = abs(math.remainder(state.heading - heading - rate * dt, 2 * math.pi))
        s = self.settings
        return dt >= s.heartbeat_s or drift > s.position_threshold_m or turn > math.radians(s.orientation_threshold_deg)

    def publish(self, state: ShipOutputs, now: float) -> None:
        if self.device is None or not self._due(state, now):
            return
        pdu = entity_state_pdu(self.settings, state, time.time())
        try:
            for host, port in self.settings.destinations():
                self.device.sendto(pdu, (host, port))
        except self.lost_errors:
            self._lost(now)
            return
        self._sent = (now, state.north, state.east, state.speed_over_ground * math.cos(state.course_over_ground),
                      state.speed_over_ground * math.sin(state.course_over_ground), state.heading,
                      state.rate_of_turn)
        self._health.outputs += 1
        self._report("tx", pdu)
