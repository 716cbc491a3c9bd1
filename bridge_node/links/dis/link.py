"""DIS link (IEEE 1278.1-2012, DIS 7): the own ship as Entity State PDUs, unicast over UDP
to the configured hosts (loopback by default; no multicast, no broadcast), with the node's
other vessels (the instructor's, scripted and logged: ``send_vessels``) as entities of
their own; and the Entity State PDUs of other simulators as other vessels, which the hub
hands to every link (the NMEA links send them as AIS targets).

- **Sending**: a PDU per entity when the heartbeat (5 s) has passed, or when the dead
  reckoning the receivers do from its last PDU (algorithm 3, rotating with constant
  velocity in world coordinates) has drifted more than 1 m in position or 3 deg in heading.
  The other vessels take the entity numbers after the own ship's, in the order they first
  appear; a vessel heard on DIS is never sent back.
- **Frames**: location and velocity are geocentric (WGS 84 ECEF, m and m/s), orientation
  the Tait-Bryan angles psi, theta, phi from the ECEF axes to the ship's body (x forward,
  y starboard, z down); the angular velocity is the body's (the yaw rate about z).
- **Receiving**: PDUs of the same exercise, entity kind platform, domain surface or
  subsurface, become vessels, dead-reckoned to the time they are read and forgotten after
  ``vessel_timeout_s`` (12 s: 2.4 heartbeats, the standard's default). Each gets an MMSI
  from ``mmsi_base`` (200 000 000: no country's MID) and its entity id. The node's own
  PDUs (its site and application), looped back, are skipped; other PDU types, exercises and entities are ``ignored``;
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
from sim_core.frames.geodesy import geodetic_to_local
from sim_core.ship.outputs import ShipOutputs

PROTOCOL_VERSION, ENTITY_STATE, ENTITY_INFORMATION_FAMILY = 7, 1, 1
PLATFORM, SURFACE, SUBSURFACE = 1, 3, 4
DR_RPW = 3  # dead reckoning: rotating, constant velocity, world coordinates
ESPDU = struct.Struct(">BBBBIHBB HHH BB BBHBBBB BBHBBBB 3f 3d 3f I B15s 3f 3f B11s I")  # 144 bytes
MAX_PDUS_PER_POLL = 1000
WGS84_A, WGS84_E2 = 6378137.0, 6.69437999014e-3
EARTH_SHELL_M = (6.30e6, 6.45e6)  # |ECEF location| of a vessel lies within this
MAX_SPEED_MPS = 100.0  # no vessel is faster: a PDU saying so is bad
DIS_KEY = "dis:"  # the keys of the vessels heard on DIS begin so
MAX_ENTITY = 65534  # entity numbers: the node's other vessels take those after the own ship's


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


@dataclass(frozen=True)
class EntityMotion:
    """What an Entity State PDU says of a vessel, SI: latitude and longitude, true heading,
    pitch (bow up +) and roll (starboard down +), course over ground (rad), speed over
    ground (m/s), yaw rate (rad/s, + to starboard)."""

    latitude: float
    longitude: float
    heading: float
    course: float
    speed: float
    rate_of_turn: float
    pitch: float = 0.0
    roll: float = 0.0

    @classmethod
    def of_ship(cls, s: ShipOutputs) -> EntityMotion:
        return cls(s.latitude, s.longitude, s.heading, s.course_over_ground, s.speed_over_ground, s.rate_of_turn,
                   s.pitch, s.roll)

    @classmethod
    def of_vessel(cls, v: Vessel) -> EntityMotion:
        return cls(v.latitude, v.longitude, v.heading, v.course_over_ground, v.speed_over_ground, v.rate_of_turn)


def entity_state_pdu(s: DisLinkSettings, motion: EntityMotion, unix_time: float, entity: int | None = None,
                     marking: str | None = None) -> bytes:
    """The Entity State PDU of the own ship (the settings' entity, type and marking), or of
    another vessel the node sends as its own ``entity`` with its ``marking`` (type: a
    surface platform, country and category 0)."""
    to_ecef = ned_to_ecef(motion.latitude, motion.longitude)
    body = to_ecef @ matrix_from_euler(motion.heading, motion.pitch, motion.roll)  # body (x fwd, y stbd, z down)
    velocity = to_ecef @ np.array([motion.speed * math.cos(motion.course), motion.speed * math.sin(motion.course), 0.0])
    location = geodetic_to_ecef(motion.latitude, motion.longitude)
    own = entity is None
    entity_type = (PLATFORM, SURFACE, *((s.country, s.category, s.subcategory) if own else (0, 0, 0)), 0, 0)
    text = s.marking if own else marking
    return ESPDU.pack(PROTOCOL_VERSION, s.exercise_id, ENTITY_STATE, ENTITY_INFORMATION_FAMILY,
                      dis_timestamp(unix_time), ESPDU.size, 0, 0, s.site, s.application, s.entity if own else entity,
                      s.force_id, 0, *entity_type, *entity_type, *velocity, *location, *euler_from_matrix(body), 0,
                      DR_RPW, b"\x00" * 15, 0.0, 0.0, 0.0, 0.0, 0.0, motion.rate_of_turn, 1,
                      text.encode("ascii", "replace")[:11].ljust(11, b"\x00"), 0)


class DeadReckoning:
    """When a sender's next PDU is due: the heartbeat passed, or the dead reckoning the
    receivers do from its last PDU (constant velocity and yaw rate) drifted past the
    settings' position or orientation threshold."""

    def __init__(self, settings: DisLinkSettings) -> None:
        self.settings = settings
        self._sent: tuple[float, EntityMotion] | None = None  # (monotonic s, motion) of the last PDU

    def due(self, motion: EntityMotion, now: float) -> bool:
        if self._sent is None:
            return True
        t, last = self._sent
        dt, s = now - t, self.settings
        north, east = geodetic_to_local(motion.latitude, motion.longitude, last.latitude, last.longitude)
        drift = math.hypot(north - last.speed * math.cos(last.course) * dt, east - last.speed * math.sin(last.course) * dt)
        turn = abs(math.remainder(motion.heading - last.heading - last.rate_of_turn * dt, 2 * math.pi))
        return dt >= s.heartbeat_s or drift > s.position_threshold_m or turn > math.radians(s.orientation_threshold_deg)

    def sent(self, motion: EntityMotion, now: float) -> None:
        self._sent = now, motion


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
        if site_app_entity[:2] == self._own[:2]:  # the node's site and application: its own ship or vessels
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
        key = DIS_KEY + "{}.{}.{}".format(*site_app_entity)
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
        self._own = DeadReckoning(settings)
        self._others: dict[int, tuple[int, DeadReckoning]] = {}  # MMSI -> (entity, its dead reckoning)

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

    def _send(self, pdu: bytes, now: float) -> bool:
        """Send a PDU to every destination; False when the socket was lost."""
        try:
            for host, port in self.settings.destinations():
                self.device.sendto(pdu, (host, port))
        except self.lost_errors:
            self._lost(now)
            return False
        self._health.outputs += 1
        self._report("tx", pdu)
        return True

    def publish(self, state: ShipOutputs, now: float) -> None:
        motion = EntityMotion.of_ship(state)
        if self.device is not None and self._own.due(motion, now) and \
                self._send(entity_state_pdu(self.settings, motion, time.time()), now):
            self._own.sent(motion, now)

    def publish_vessels(self, vessels: list[Vessel], now: float) -> None:
        """The node's other vessels (the instructor's, scripted and logged; not those heard
        on DIS, which their own simulators send), each as an entity of its own numbered on
        from the own ship's, in the order they first appear."""
        if self.device is None or not self.settings.send_vessels:
            return
        for v in vessels:
            if v.key.startswith(DIS_KEY) or not v.fix_valid:
                continue
            if v.mmsi not in self._others:
                self._others[v.mmsi] = self.settings.entity + 1 + len(self._others), DeadReckoning(self.settings)
            entity, reckoning = self._others[v.mmsi]
            motion = EntityMotion.of_vessel(v)
            if entity <= MAX_ENTITY and reckoning.due(motion, now) and self._send(
                    entity_state_pdu(self.settings, motion, time.time(), entity, v.name or str(v.mmsi)), now):
                reckoning.sent(motion, now)
