"""NMEA 2000 network management (ISO 11783-5 as NMEA 2000 uses it): the node's NAME, its
address claim and defence, the answers to ISO requests, and the heartbeat. Chart plotters
list only sources that claim an address and answer these requests.

- **Claim**: at start the node claims its preferred address (PGN 60928, the 64-bit NAME).
  Addresses 0..127 and 248..253 may be used at once; others only 250 ms after the claim.
- **Defence**: a claim for the node's address from another NAME is a conflict; the lower
  NAME wins. Winning, the node claims again; losing, it claims the next address no claim
  names (if arbitrary-address capable), or sends "cannot claim" (its NAME from the null
  address 254) and goes silent. Every move and the silence are logged.
- **ISO requests** (PGN 59904) to the node or to all: address claim, product information
  (126996), the PGN lists (126464) and the heartbeat (126993) are answered; a request to
  the node for a PGN it does not send is refused (59392 NAK). The node's periodic outputs
  come at their rates anyway.
- **Heartbeat** (126993) every ``heartbeat_s``.

The frames are fixed layouts packed here with ``int`` and ``struct``; the tests decode them
with the independent nmea2000 package (canboat's database).
"""
from __future__ import annotations

import logging
import socket
import struct
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version

from pydantic import Field

from sim_core.params import Params

log = logging.getLogger("icebridge.links")
ADDRESS_CLAIM, ISO_REQUEST, ISO_ACKNOWLEDGEMENT = 60928, 59904, 59392
PRODUCT_INFORMATION, PGN_LIST, HEARTBEAT = 126996, 126464, 126993
NETWORK_PGNS = frozenset({ADDRESS_CLAIM, ISO_REQUEST})  # taken from any device, not orders
TRANSMITTED = (ADDRESS_CLAIM, ISO_ACKNOWLEDGEMENT, PRODUCT_INFORMATION, PGN_LIST, HEARTBEAT)
FAST_PACKET_PGNS = frozenset({PRODUCT_INFORMATION, PGN_LIST})
# priorities of canboat's PGN database (canboat's own docs/canboat.json, not in this repository)
PRIORITY = {ADDRESS_CLAIM: 6, ISO_REQUEST: 6, ISO_ACKNOWLEDGEMENT: 6, PRODUCT_INFORMATION: 6, PGN_LIST: 6,
            HEARTBEAT: 7}
NULL_ADDRESS, GLOBAL_ADDRESS = 254, 255
CLAIMABLE = range(0, 252)  # 252 is reserved, 253 the null of some stacks, 254 null, 255 global
CLAIM_WAIT_S = 0.25  # an address of 128..247 is used only this long after its claim
NMEA2000_VERSION = 2100  # 2.100, in units of 0.001
NAK = 1  # ISO acknowledgement control: negative


def _host_identity() -> int:
    """A 21-bit identity number from the host name, so that two nodes on one bus differ."""
    return zlib.crc32(socket.gethostname().encode()) & 0x1FFFFF


def _software_version() -> str:
    try:
        return f"IceBridge {version('icebridge')}"
    except PackageNotFoundError:
        return "IceBridge"


class N2kName(Params):
    """The node's ISO NAME (PGN 60928). The defaults describe a navigation source (device
    class 60, function 170 integrated navigation) of the marine industry; 2046 is no
    registered manufacturer's code: an installation with its own code sets it here."""

    identity_number: int = Field(default_factory=_host_identity, ge=0, le=0x1FFFFF,
                                 description="unique per device; default: from the host name")
    manufacturer_code: int = Field(2046, ge=0, le=2047)
    device_instance: int = Field(0, ge=0, le=255, description="ECU instance (3 bits) and function instance (5)")
    device_function: int = Field(170, ge=0, le=255)
    device_class: int = Field(60, ge=0, le=127)
    system_instance: int = Field(0, ge=0, le=15)
    industry_group: int = Field(4, ge=0, le=7, description="4: marine")
    arbitrary_address_capable: bool = True

    def value(self) -> int:
        """The 64-bit NAME; lower NAMEs win address conflicts."""
        return (self.identity_number | self.manufacturer_code << 21 | self.device_instance << 32
                | self.device_function << 40 | self.device_class << 49 | self.system_instance << 56
                | self.industry_group << 60 | int(self.arbitrary_address_capable) << 63)


class N2kProduct(Params):
    """Product information (PGN 126996): strings of at most 32 ASCII characters."""

    product_code: int = Field(1, ge=0, le=65533)
    model_id: str = Field("IceBridge simulator node", max_length=32, pattern=r"^[\x20-\x7e]*$")
    software_version: str = Field(default_factory=_software_version, max_length=32, pattern=r"^[\x20-\x7e]*$")
    model_version: str = Field("1", max_length=32, pattern=r"^[\x20-\x7e]*$")
    serial_code: str = Field("", max_length=32, pattern=r"^[\x20-\x7e]*$")
    certification_level: int = Field(0, ge=0, le=2)
    load_equivalency: int = Field(1, ge=0, le=255, description="bus current in units of 50 mA")


@dataclass(frozen=True)
class Frame:
    """One PGN to send: priority, PGN, source and destination addresses, payload."""

    priority: int
    pgn: int
    source: int
    destination: int
    payload: bytes


def _fixed(text: str) -> bytes:
    return text.encode("ascii").ljust(32, b"\xff")


class NetworkManager:
    """Claims and defends an address, answers ISO requests and sends the heartbeat.
    Driven by the link's clock (``now``, monotonic s): ``tick`` each poll, ``on_frame`` for
    each network frame received; both return the frames to send."""

    def __init__(self, name: N2kName, preferred: int, product: N2kProduct, heartbeat_s: float,
                 transmit: Sequence[int], receive: Sequence[int]) -> None:
        self.name, self.name_value, self.preferred = name, name.value(), preferred
        self.product, self.heartbeat_s = product, heartbeat_s
        self.transmit = sorted(set(transmit) | set(TRANSMITTED))
        self.receive = sorted(set(receive) | NETWORK_PGNS)
        self.others: dict[int, int] = {}  # address -> NAME of the other devices' claims
        self.restart()

    def restart(self) -> None:
        """Start over (a reopened bus): claim again at the next tick."""
        self.state = "idle"  # idle, claiming, claimed, cannot_claim
        self.address: int | None = self.preferred
        self.claimed_at = 0.0
        self._heartbeat_due = 0.0
        self._heartbeat_seq = 0
        self.others.clear()

    @property
    def can_send(self) -> bool:
        """Whether the node may send its outputs now."""
        return self.state == "claimed" or (self.state == "claiming" and not 128 <= self.address <= 247)

    def tick(self, now: float) -> list[Frame]:
        """The claim at start, the end of a claim's wait, and the heartbeat when due."""
        if self.state == "idle":
            return self._claim(self.preferred, now)
        if self.state == "claiming" and now - self.claimed_at >= CLAIM_WAIT_S:
            self.state = "claimed"
            log.info("NMEA 2000: address %d claimed (NAME %016x)", self.address, self.name_value)
        if self.state == "claimed" and now >= self._heartbeat_due:
            self._heartbeat_due = now + self.heartbeat_s
            return [self._heartbeat()]
        return []

    def on_frame(self, pgn: int, source: int, destination: int, data: bytes, now: float) -> list[Frame] | None:
        """Answer one address claim or ISO request; None if the frame's length is wrong."""
        if pgn == ADDRESS_CLAIM:
            return self._on_claim(source, int.from_bytes(data, "little"), now) if len(data) == 8 else None
        if len(data) < 3:
            return None
        return self._on_request(source, destination, int.from_bytes(data[:3], "little"))

    def _claim(self, address: int, now: float) -> list[Frame]:
        self.state, self.address, self.claimed_at = "claiming", address, now
        return [self._claim_frame()]

    def _claim_frame(self) -> Frame:
        source = NULL_ADDRESS if self.state == "cannot_claim" else self.address
        return Frame(PRIORITY[ADDRESS_CLAIM], ADDRESS_CLAIM, source, GLOBAL_ADDRESS,
                     self.name_value.to_bytes(8, "little"))

    def _on_claim(self, source: int, name: int, now: float) -> list[Frame]:
        if name == self.name_value or source == NULL_ADDRESS:  # our own echoed, or another's cannot-claim
            return []
        for address in [a for a, n in self.others.items() if n == name]:
            del self.others[address]  # that device moved
        self.others[source] = name
        if source != self.address or self.state in ("idle", "cannot_claim"):
            return []
        if self.name_value < name:  # ours wins: claim again, the other must move
            return [self._claim_frame()]
        lost = self.address
        free = [a for a in (*range(lost + 1, CLAIMABLE.stop), *range(0, lost)) if a not in self.others]
        if self.name.arbitrary_address_capable and free:
            log.warning("NMEA 2000: address %d lost to NAME %016x; claiming %d", lost, name, free[0])
            return self._claim(free[0], now)
        self.state, self.address = "cannot_claim", None
        log.error("NMEA 2000: address %d lost to NAME %016x and no address free: cannot claim, silent", lost, name)
        return [self._claim_frame()]

    def _on_request(self, source: int, destination: int, pgn: int) -> list[Frame]:
        to_us = destination == self.address and self.state in ("claiming", "claimed")
        if not (to_us or destination == GLOBAL_ADDRESS):
            return []
        if pgn == ADDRESS_CLAIM:
            return [] if self.state == "idle" else [self._claim_frame()]
        if not self.can_send:
            return []
        reply = {PRODUCT_INFORMATION: lambda: [self._product_information()], PGN_LIST: self._pgn_lists,
                 HEARTBEAT: lambda: [self._heartbeat()]}.get(pgn)
        if reply is not None:
            return reply()
        if to_us and pgn not in self.transmit:
            payload = struct.pack("<BB3s", NAK, 0xFF, b"\xff\xff\xff") + pgn.to_bytes(3, "little")
            return [Frame(PRIORITY[ISO_ACKNOWLEDGEMENT], ISO_ACKNOWLEDGEMENT, self.address, source, payload)]
        return []

    def _product_information(self) -> Frame:
        p = self.product
        payload = (struct.pack("<HH", NMEA2000_VERSION, p.product_code) + _fixed(p.model_id)
                   + _fixed(p.software_version) + _fixed(p.model_version) + _fixed(p.serial_code)
                   + bytes([p.certification_level, p.load_equivalency]))
        return Frame(PRIORITY[PRODUCT_INFORMATION], PRODUCT_INFORMATION, self.address, GLOBAL_ADDRESS, payload)

    def _pgn_lists(self) -> list[Frame]:
        """The transmit list (function code 0) and the receive list (1)."""
        return [Frame(PRIORITY[PGN_LIST], PGN_LIST, self.address, GLOBAL_ADDRESS,
                      bytes([code]) + b"".join(p.to_bytes(3, "little") for p in pgns))
                for code, pgns in ((0, self.transmit), (1, self.receive))]

    def _heartbeat(self) -> Frame:
        """Interval (ms), sequence counter, controller states and equipment status 0 (error
        active, operational), the reserved bits all ones."""
        self._heartbeat_seq = (self._heartbeat_seq + 1) % 253
        payload = struct.pack("<HBB", round(self.heartbeat_s * 1000), self._heartbeat_seq, 0xC0) + b"\xff" * 4
        return Frame(PRIORITY[HEARTBEAT], HEARTBEAT, self.address, GLOBAL_ADDRESS, payload)
