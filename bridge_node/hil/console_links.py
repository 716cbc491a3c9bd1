"""The software console's ends, one per link kind, each the peer of one node link.

A ``ConsoleLink`` holds the latest order of each channel (rudder, engine, each searchlight)
and sends it again at ``rate_hz``, as a console repeats its state; ``poll`` reads back the
instrument outputs as ``Reading`` rows (SI) and ALR alarms as ``AlarmReading`` rows. Faults
(``inject``) act on the outgoing traffic of one end, as a faulty console or cable would: the
console is the one sending the faulty traffic, the node is left as it is. Like the node's links, an end is a
context manager, and closing twice is safe.
"""
from __future__ import annotations

import asyncio
import heapq
import itertools
import math
import random
import threading
import time
from abc import ABC, abstractmethod
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, replace

import can
import serial
from pymodbus.server import ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

from bridge_node.hil.scenario import Fault
from bridge_node.hil.settings import CanConsoleSettings, ModbusConsoleSettings, NmeaConsoleSettings
from bridge_node.links.messages import ETL_POSITIONS
from bridge_node.links.can_link import N2K_DBC, dbc_path, load_dbc
from bridge_node.links.modbus_link import raw_register, register_value
from bridge_node.links.n2k_frames import identifier, parse_identifier
from bridge_node.links.nmea0183 import ETL, PRC, ROR, SEARCHLIGHT_SENTENCE, checksum
from bridge_node.node.errors import UserError
from sim_core.ship.orders import OrderKind
from sim_core.ship.searchlights import SearchlightOrder

ETL_CODES = {name: code for code, name in ETL_POSITIONS.items()}  # telegraph position -> ETL code
# corrupt = "range" sends these
OUT_OF_RANGE = {OrderKind.RUDDER: math.radians(120.0), OrderKind.LEVER: 150.0, OrderKind.TELEGRAPH: "99"}
OUT_OF_RANGE_BEARING = math.radians(200.0)  # and a searchlight order trained this far
CHANNEL = {OrderKind.RUDDER: "rudder", OrderKind.TELEGRAPH: "engine", OrderKind.LEVER: "engine"}
DEVICE_ERRORS = (OSError, can.CanError, serial.SerialException)  # a port, bus or server that failed


@dataclass(frozen=True)
class Order:
    """A console order: ``kind`` OrderKind.RUDDER (value rad, + starboard), OrderKind.TELEGRAPH (a position
    name), OrderKind.LEVER (percent) or OrderKind.SEARCHLIGHT (a ``SearchlightOrder`` with every field given)."""

    kind: str
    value: float | str | SearchlightOrder

    @property
    def channel(self) -> str:
        """The channel whose latest order this is: rudder, engine, or one searchlight's."""
        return f"searchlight {self.value.index}" if self.kind == OrderKind.SEARCHLIGHT else CHANNEL[self.kind]

    def wire_value(self, corrupt: str | None) -> float | str | SearchlightOrder:
        """The value to send: the order's, or with corrupt = "range" one out of range."""
        if corrupt != "range":
            return self.value
        if self.kind == OrderKind.SEARCHLIGHT:
            return replace(self.value, bearing=OUT_OF_RANGE_BEARING)
        return OUT_OF_RANGE[self.kind]


@dataclass(frozen=True)
class Reading:
    """One instrument value read back: console monotonic time s, console end, quantity
    (rudder_angle rad, shaft_speed rev/s, heading rad, rate_of_turn rad/s) and value."""

    time: float
    role: str
    quantity: str
    value: float


@dataclass(frozen=True)
class AlarmReading:
    """One ALR sentence read back: time s, console end, alarm number, active, text."""

    time: float
    role: str
    number: int
    active: bool
    text: str


class ConsoleLink(ABC):
    """One console end: orders out (held and repeated), instrument outputs in, faults."""

    kind: str = ""  # link type, as in the node's settings
    corruptions: tuple[str, ...] = ("range",)  # the ``corrupt`` kinds this end can send
    framing: str | None = None  # what corrupt = "format" sends on this end (one of corruptions)
    garbage_kind: str | None = None  # what a garbage burst is on this end; None: none

    def __init__(self, settings) -> None:
        self.settings = settings
        self.role: str = settings.role
        self.device = None
        self.held: dict[str, Order] = {}  # channel -> latest order
        self.sent = Counter()  # orders given (corrupted, duplicated, dropped, delayed), garbage, frames written
        self._faults: list[tuple[Fault, random.Random]] = []
        self._delayed: list[tuple[float, int, object]] = []  # (due s, sequence, wire item)
        self._sequence = itertools.count()
        self._next_repeat = -math.inf
        self._active = False

    # --- life cycle ---

    def open(self) -> None:
        """Open the console's end of the link (a port, bus or server); UserError with the
        operating system's or the library's own message if it cannot be opened."""
        try:
            self.device = self._open()
        except (*DEVICE_ERRORS, ValueError, ImportError) as exc:
            raise UserError(f"console end {self.role} ({self.kind}): cannot open it: {exc}") from None
        self._active = True

    def close(self) -> None:
        """Release the end; safe to call twice."""
        self._active = False
        self._release()

    def __enter__(self) -> ConsoleLink:
        self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _release(self) -> None:
        """Close the device; one already lost (its port gone) is let go without a word."""
        device, self.device = self.device, None
        if device is not None:
            try:
                self._close(device)
            except DEVICE_ERRORS:
                pass

    # --- orders and faults ---

    def unsupported(self, fault: Fault) -> str | None:
        """Why this end cannot inject ``fault``, or None."""
        if fault.kind == "corrupt" and fault.corrupt not in self.corruptions + (("format",) if self.framing else ()):
            return f"corrupt = {fault.corrupt!r} does not apply to a {self.kind} link (allowed: {self.corruptions})"
        if fault.kind == "garbage" and self.garbage_kind is None:
            return f"a garbage burst does not apply to a {self.kind} link"
        if fault.kind == "bus_off":
            return "bus_off needs the CAN adapter's pty pair, which icebridge hil run creates"
        return None

    def supports(self, kind: str) -> bool:
        """Whether this end can give orders of ``kind``."""
        return True

    def order(self, order: Order, now: float) -> None:
        """Hold ``order`` as its channel's latest and send it now (``now``: monotonic s)."""
        self.held[order.channel] = order
        self._send(order, now)

    def inject(self, fault: Fault, rng: random.Random) -> None:
        """Start ``fault``; it lasts until ``clear`` (the caller keeps the scenario's clock)."""
        self._faults.append((fault, rng))
        if fault.kind == "garbage" and self.device is not None:
            self._write_guarded(self._garbage(rng, fault.count))
            self.sent["garbage"] += fault.count
        if fault.kind == "disconnect":
            self._release()

    def clear(self, fault: Fault) -> None:
        """End ``fault``; a disconnected end is opened again at the next ``tick``."""
        self._faults = [(f, r) for f, r in self._faults if f is not fault]

    def tick(self, now: float) -> list[Reading | AlarmReading]:
        """Reopen after a disconnect, repeat the held orders when due, send delayed traffic,
        and read what came in (``now``: monotonic s)."""
        disconnected = any(f.kind == "disconnect" for f, _ in self._faults)
        if self.device is None and self._active and not disconnected:
            try:
                self.device = self._open()
            except DEVICE_ERRORS:
                return []
        if self.device is None:
            return []
        if now >= self._next_repeat:
            self._next_repeat = now + 1.0 / self.settings.rate_hz
            for order in list(self.held.values()):
                self._send(order, now)
        while self._delayed and self._delayed[0][0] <= now:
            self._write_guarded([heapq.heappop(self._delayed)[2]])
        if self.device is None:  # a write above failed and released the device
            return []
        try:
            return self._read(time.monotonic())  # stamped when read
        except DEVICE_ERRORS:
            self._release()
            return []

    def _send(self, order: Order, now: float) -> None:
        """One order through the active faults: dropped, corrupted, duplicated, delayed."""
        corrupt, copies, delay = None, 1, 0.0
        for fault, rng in self._faults:
            if fault.kind not in ("drop", "corrupt", "duplicate", "delay") or rng.random() >= fault.probability:
                continue
            if fault.kind == "drop":
                self.sent["dropped"] += 1
                return
            if fault.kind == "corrupt":
                corrupt = fault.corrupt
            elif fault.kind == "duplicate":
                copies = 2
            else:
                delay = max(delay, fault.delay_s)
        corrupt = self.framing if corrupt == "format" else corrupt
        items = self._encode(order, corrupt) * copies
        self.sent["orders"] += 1
        if corrupt:
            self.sent["corrupted"] += 1
        if copies > 1:
            self.sent["duplicated"] += 1
        if delay:
            self.sent["delayed"] += 1
            for item in items:
                heapq.heappush(self._delayed, (now + delay, next(self._sequence), item))
        else:
            self._write_guarded(items)

    def _write_guarded(self, items: list) -> None:
        """Write wire items; a device that fails is released (and reopened at the next tick)."""
        if self.device is None:
            return
        try:
            for item in items:
                self._write(item)
                self.sent["frames"] += 1
        except DEVICE_ERRORS:
            self.sent["write_failed"] += 1
            self._release()

    # --- for the link kinds ---

    @abstractmethod
    def _open(self):
        """Open and return the port, bus or server."""

    @abstractmethod
    def _close(self, device) -> None:
        """Release the port, bus or server."""

    @abstractmethod
    def _encode(self, order: Order, corrupt: str | None) -> list:
        """The wire items (frames, sentences, register writes) of one order."""

    @abstractmethod
    def _write(self, item) -> None:
        """Send one wire item on the open device."""

    def _garbage(self, rng: random.Random, count: int) -> list:
        """``count`` random wire items (default: none)."""
        return []

    @abstractmethod
    def _read(self, now: float) -> list[Reading | AlarmReading]:
        """What the node sent since the last read."""


# PGN -> (N2K DBC message, signal, quantity, SI per DBC unit)
N2K_READINGS = {127245: ("Rudder", "Position", "rudder_angle", 1.0),
                127488: ("EngineRapid", "Speed", "shaft_speed", 1.0 / 60.0),
                127250: ("VesselHeading", "Heading", "heading", 1.0),
                127251: ("RateOfTurn", "Rate", "rate_of_turn", 1.0)}
HELM_PGN, ENGINE_PGN, SEARCHLIGHT_PGN, CONSOLE_PRIORITY = 0xFF50, 0xFF51, 0xFF52, 6


class CanConsole(ConsoleLink):
    """The console on a python-can bus (slcan on a pty, socketcan vcan0, ...)."""

    kind = "can"
    corruptions = ("dlc", "range")
    framing = "dlc"
    garbage_kind = "frames with random 11-bit identifiers and data"

    def __init__(self, settings: CanConsoleSettings) -> None:
        super().__init__(settings)
        self.dbc = load_dbc(dbc_path(settings.dbc))
        self.n2k = load_dbc(N2K_DBC)
        self._counter = 0

    def _open(self) -> can.BusABC:
        s = self.settings
        extra = {"sleep_after_open": s.open_delay_s} if s.interface == "slcan" else {}
        return can.Bus(interface=s.interface, channel=s.channel, bitrate=s.bitrate, **extra)

    def _close(self, bus: can.BusABC) -> None:
        bus.shutdown()

    def _encode(self, order: Order, corrupt: str | None) -> list[can.Message]:
        value = order.wire_value(corrupt)
        s = self.settings
        if order.kind == OrderKind.RUDDER and s.helm == "pgn127245":
            raw = int(round(value / 1e-4)) & 0xFFFF
            data = bytes([0, 0xF8 | (1 if value > 0 else 2), raw & 0xFF, raw >> 8, 0xFF, 0x7F, 0xFF, 0xFF])
            can_id = identifier(2, 127245, s.source_address)
        elif order.kind == OrderKind.RUDDER:
            self._counter = (self._counter + 1) % 256
            data = self.dbc.get_message_by_name("HelmOrder").encode(
                {"RudderOrder": math.degrees(value), "Status": 1, "Counter": self._counter}, strict=False)
            can_id = identifier(CONSOLE_PRIORITY, HELM_PGN, s.source_address)
        elif order.kind == OrderKind.SEARCHLIGHT:
            data = self.dbc.get_message_by_name("SearchlightOrder").encode(
                {"Light": value.index, "Lamp": int(value.on), "Bearing": math.degrees(value.bearing),
                 "Elevation": math.degrees(value.elevation), "Counter": 0}, strict=False)
            can_id = identifier(CONSOLE_PRIORITY, SEARCHLIGHT_PGN, s.source_address)
        else:
            telegraph = order.kind == OrderKind.TELEGRAPH
            code = (int(value) if corrupt == "range" else int(ETL_CODES[value])) if telegraph else 0
            data = self.dbc.get_message_by_name("EngineOrder").encode(
                {"Engine": 0, "Lever": 0.0 if telegraph else value, "TelegraphPosition": code,
                 "Mode": 1 if telegraph else 0}, strict=False)
            can_id = identifier(CONSOLE_PRIORITY, ENGINE_PGN, s.source_address)
        if corrupt == "dlc":
            data = data[:4]
        return [can.Message(arbitration_id=can_id, data=data, is_extended_id=True)]

    def _write(self, msg: can.Message) -> None:
        self.device.send(msg, timeout=0.1)

    def _garbage(self, rng: random.Random, count: int) -> list[can.Message]:
        return [can.Message(arbitration_id=rng.randrange(0x800), is_extended_id=False,
                            data=bytes(rng.randrange(256) for _ in range(rng.randrange(9)))) for _ in range(count)]

    def _read(self, now: float) -> list[Reading]:
        out = []
        while (msg := self.device.recv(timeout=0.0)) is not None:
            if not msg.is_extended_id or msg.is_error_frame:
                continue
            spec = N2K_READINGS.get(parse_identifier(msg.arbitration_id)[1])
            if spec is None or len(msg.data) != 8:
                continue
            message, signal, quantity, factor = spec
            value = self.n2k.get_message_by_name(message).decode(bytes(msg.data), decode_choices=False)[signal]
            out.append(Reading(now, self.role, quantity, float(value) * factor))
        return out


# sentence type -> (field index, quantity, SI per unit)
NMEA_READINGS = {"RSA": (0, "rudder_angle", math.radians(1.0)), "RPM": (2, "shaft_speed", 1.0 / 60.0),
                 "HDT": (0, "heading", math.radians(1.0)), "ROT": (0, "rate_of_turn", math.radians(1.0) / 60.0)}
MAX_LINE = 1024  # characters of a line without its end: beyond this it is noise


class NmeaConsole(ConsoleLink):
    """The console on a serial NMEA 0183 line (pyserial: a port or a pty)."""

    kind = "nmea0183"
    corruptions = ("checksum", "range")
    framing = "checksum"
    garbage_kind = "random bytes"

    def __init__(self, settings: NmeaConsoleSettings) -> None:
        super().__init__(settings)
        self._pending = b""

    def _open(self) -> serial.SerialBase:
        return serial.serial_for_url(self.settings.port, baudrate=self.settings.baudrate, timeout=0, write_timeout=1.0)

    def _close(self, port: serial.SerialBase) -> None:
        port.close()

    def _encode(self, order: Order, corrupt: str | None) -> list[bytes]:
        value = order.wire_value(corrupt)
        talker = self.settings.talker
        if order.kind == OrderKind.RUDDER:
            sentence = str(ROR(talker, "ROR", (f"{math.degrees(value):.1f}", "A", "", "V", "B")))
        elif order.kind == OrderKind.SEARCHLIGHT:
            body = (f"{SEARCHLIGHT_SENTENCE},{value.index},{'A' if value.on else 'V'},"
                    f"{math.degrees(value.bearing):.1f},{math.degrees(value.elevation):.1f}")
            sentence = f"${body}*{checksum(body):02X}"
        elif order.kind == OrderKind.TELEGRAPH:
            code = value if corrupt == "range" else ETL_CODES[value]
            sentence = str(ETL(talker, "ETL", ("", "O", code, "", "B", "0")))
        else:
            sentence = str(PRC(talker, "PRC", (f"{value:.1f}", "A", "", "V", "", "V", "B", "0")))
        if corrupt == "checksum":
            body, given = sentence.rsplit("*", 1)
            sentence = f"{body}*{int(given, 16) ^ 0x55:02X}"
        return [(sentence + "\r\n").encode("ascii")]

    def _write(self, data: bytes) -> None:
        self.device.write(data)

    def _garbage(self, rng: random.Random, count: int) -> list[bytes]:
        return [bytes(rng.randrange(256) for _ in range(count))]

    def _read(self, now: float) -> list[Reading | AlarmReading]:
        waiting = self.device.in_waiting
        lines = (self._pending + (self.device.read(waiting) if waiting else b"")).split(b"\n")
        self._pending = lines.pop()[-MAX_LINE:]
        out = []
        for raw in lines:
            line = raw.decode("ascii", errors="replace").strip()
            if not line.startswith("$") or "*" not in line:
                continue
            body, given = line[1:].rsplit("*", 1)
            try:
                if checksum(body) != int(given, 16):
                    continue
            except ValueError:
                continue
            fields = body.split(",")
            kind = fields[0][2:]
            try:
                if kind == "ALR":
                    out.append(AlarmReading(now, self.role, int(fields[2]), fields[3] == "A", fields[5]))
                elif kind in NMEA_READINGS:
                    index, quantity, factor = NMEA_READINGS[kind]
                    out.append(Reading(now, self.role, quantity, float(fields[1 + index]) * factor))
            except (ValueError, IndexError):
                continue
        return out


READ_HOLDING, WRITE_MULTIPLE = 3, 16  # Modbus function codes
REGISTERS = 100
UNWRITTEN = 0x8000  # an indicator register the node has not written yet holds this
# indicator -> (quantity, SI per engineering unit); "speed" has no quantity here
INDICATORS = {"rudder_angle": ("rudder_angle", math.radians(1.0)), "shaft_rpm": ("shaft_speed", 1.0 / 60.0),
              "heading": ("heading", math.radians(1.0))}


MBAP_FAULTS = ("length", "protocol", "transaction", "truncated")  # what a malformed reply gets wrong


def mangle_mbap(frame: bytes, rng: random.Random) -> bytes:
    """A Modbus TCP frame with its MBAP header made wrong, one way drawn from ``rng``: a
    length field that does not match what follows, a protocol id other than 0, another
    request's transaction id, or the frame cut short."""
    how = rng.choice(MBAP_FAULTS)
    b = bytearray(frame)
    if how == "length":
        b[4:6] = max(0, int.from_bytes(b[4:6], "big") + rng.choice((-2, -1, 1, 3))).to_bytes(2, "big")
    elif how == "protocol":
        b[2:4] = rng.randrange(1, 0x10000).to_bytes(2, "big")
    elif how == "transaction":
        b[0:2] = ((int.from_bytes(b[0:2], "big") + rng.randrange(1, 0x10000)) & 0xFFFF).to_bytes(2, "big")
    else:
        del b[rng.randrange(1, len(b)):]
    return bytes(b)


class _RegisterServer:
    """A pymodbus TCP server (device registers 0..99) in a thread with its own event loop;
    ``trace_packet(sending, frame) -> frame`` sees (and may change) every frame."""

    def __init__(self, host: str, port: int, device_id: int, values: list[int],
                 trace_packet: Callable[[bool, bytes], bytes]) -> None:
        self.device_id = device_id
        self._server = None
        self._loop = None
        ready = threading.Event()
        device = SimDevice(device_id, [SimData(0, count=REGISTERS, values=values, datatype=DataType.REGISTERS)])

        async def serve() -> None:
            self._server = ModbusTcpServer(device, address=(host, port), trace_packet=trace_packet)
            self._loop = asyncio.get_running_loop()
            self._loop.call_soon(ready.set)
            await self._server.serve_forever()

        self._thread = threading.Thread(target=asyncio.run, args=(serve(),), daemon=True, name="console-modbus")
        self._thread.start()
        if not ready.wait(5.0):
            raise OSError(f"the Modbus server on {host}:{port} did not start")

    def _call(self, coro):
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(5.0)

    def set(self, address: int, raw: int) -> None:
        self._call(self._server.async_setValues(self.device_id, WRITE_MULTIPLE, address, [raw & 0xFFFF]))

    def values(self) -> list[int]:
        return list(self._call(self._server.async_getValues(self.device_id, READ_HOLDING, 0, REGISTERS)))

    def stop(self) -> None:
        self._call(self._server.shutdown())
        self._thread.join(5.0)


class ModbusConsole(ConsoleLink):
    """The console's register server: the node polls its order registers and writes its
    indicators; register values survive a disconnect, as a PLC's do. Its framing fault
    (corrupt = "format") is on the replies the node reads: malformed MBAP headers."""

    kind = "modbus"
    corruptions = ("format", "range")

    def __init__(self, settings: ModbusConsoleSettings) -> None:
        super().__init__(settings)
        self._values = [0] * REGISTERS
        for w in settings.writes:
            self._values[w.address] = UNWRITTEN
        self._bad_replies: tuple[Fault, random.Random] | None = None  # corrupt = "format", while on

    def inject(self, fault: Fault, rng: random.Random) -> None:
        if fault.kind == "corrupt" and fault.corrupt == "format":
            self._bad_replies = (fault, rng)
        else:
            super().inject(fault, rng)

    def clear(self, fault: Fault) -> None:
        if self._bad_replies is not None and self._bad_replies[0] is fault:
            self._bad_replies = None
        super().clear(fault)

    def _trace(self, sending: bool, frame: bytes) -> bytes:
        """Every frame of the server (on its thread): a reply, while corrupt = "format" is
        on, made malformed with the fault's probability."""
        bad = self._bad_replies
        if not sending or bad is None or bad[1].random() >= bad[0].probability:
            return frame
        self.sent["bad_replies"] += 1
        return mangle_mbap(frame, bad[1])

    def supports(self, kind: str) -> bool:
        return any(r.order.split("_")[0] == kind for r in self.settings.registers)  # searchlight_on: searchlight

    def _open(self) -> _RegisterServer:
        s = self.settings
        return _RegisterServer(s.host, s.port, s.device_id, list(self._values), self._trace)

    def _close(self, server: _RegisterServer) -> None:
        self._values = server.values()
        server.stop()

    def _encode(self, order: Order, corrupt: str | None) -> list[tuple[int, int]]:
        value = order.wire_value(corrupt)
        out = []
        if order.kind == OrderKind.SEARCHLIGHT:
            fields = {"searchlight_on": float(value.on), "searchlight_bearing": math.degrees(value.bearing),
                      "searchlight_elevation": math.degrees(value.elevation)}
            return [(r.address, raw_register(fields[r.order] / r.scale, r.type)) for r in self.settings.registers
                    if r.order in fields and r.light == value.index]
        for r in self.settings.registers:
            if r.order != order.kind:
                continue
            eng = math.degrees(value) if order.kind == OrderKind.RUDDER else (
                int(value if corrupt == "range" else ETL_CODES[value]) if order.kind == OrderKind.TELEGRAPH else value)
            out.append((r.address, raw_register(eng / r.scale, r.type)))
        return out

    def _write(self, item: tuple[int, int]) -> None:
        self.device.set(*item)

    def _read(self, now: float) -> list[Reading]:
        values = self.device.values()
        out = []
        for w in self.settings.writes:
            raw = values[w.address]
            if raw != UNWRITTEN and w.value in INDICATORS:
                quantity, factor = INDICATORS[w.value]
                out.append(Reading(now, self.role, quantity, register_value(raw, w.type) * w.scale * factor))
        return out


CONSOLE_LINKS = {"can": CanConsole, "nmea0183": NmeaConsole, "modbus": ModbusConsole}


def make_console_link(settings) -> ConsoleLink:
    """The console end for one ``[[links]]`` table of a console config."""
    return CONSOLE_LINKS[settings.type](settings)
