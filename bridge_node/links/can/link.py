"""CAN link (python-can): console frames in (decoded with the user's DBC), NMEA 2000 PGN
127245 rudder orders in as a helm source, and the ship's state out as NMEA 2000 PGNs
127245, 127488, 127489 (fast packet), 127250, 127251, 127257, 129025, 129026 at their rates and
at the priorities of canboat's database. The node is an NMEA 2000 citizen: it claims and
defends its address, answers ISO requests and sends its heartbeat (``n2k_network``). Over a
serial line (slcan) the frames come in through a reader thread and go out through a writer
thread: the loop never waits for a port that is silent, nor for a far end that does not read."""
from __future__ import annotations

import functools
import math
import time
from collections.abc import Iterator
from pathlib import Path

import can
import cantools

from bridge_node.links.base import Link
from bridge_node.links.device_io import QueuedReader, QueuedWriter, RateSchedule
from bridge_node.links.messages import ETL_POSITIONS, ControlInput, searchlight_order
from bridge_node.links.can.n2k_frames import fast_packet_frames, identifier, parse_identifier
from bridge_node.links.can.n2k_network import FAST_PACKET_PGNS, GLOBAL_ADDRESS, NETWORK_PGNS, Frame, NetworkManager
from bridge_node.links.can.settings import CanLinkSettings
from sim_core.ship.orders import OrderKind
from sim_core.ship.outputs import ShipOutputs

CONFIG_DIR = Path(__file__).resolve().parents[3] / "config"  # the project's config folder
N2K_DBC = CONFIG_DIR / "nmea2000.dbc"
ID_MASK = 0x03FFFF00  # match any priority and source
MAX_FRAMES_PER_POLL = 1000
RUDDER_PGN = 127245
# output name -> (DBC message, PGN, priority); the priorities of canboat's PGN database
# (docs/canboat.json in canboat's repository, not in this one)
OUTPUTS = {"rudder": ("Rudder", 127245, 2), "engine_rapid": ("EngineRapid", 127488, 2),
           "engine_dynamic": ("EngineDynamic", 127489, 2), "heading": ("VesselHeading", 127250, 2),
           "rate_of_turn": ("RateOfTurn", 127251, 2), "position": ("PositionRapid", 129025, 2),
           "cog_sog": ("CogSogRapid", 129026, 2), "attitude": ("Attitude", 127257, 3)}
FAST_PGNS = FAST_PACKET_PGNS | {127489}


@functools.cache
def load_dbc(path: Path) -> cantools.database.can.Database:
    """A DBC whose frames match any priority and source address (loaded once per path; read only)."""
    return cantools.database.load_file(str(path), frame_id_mask=ID_MASK, strict=False)


def dbc_path(value: str) -> Path:
    """The console DBC of the settings: an absolute path as is, a relative one in ``config/``."""
    path = Path(value).expanduser()
    return path if path.is_absolute() else CONFIG_DIR / path


NOT_AVAILABLE_I32 = 0x7FFFFFFF  # a signed 32-bit NMEA 2000 field's "not available"


def _n2k_fields(name: str, s: ShipOutputs, sid: int) -> dict:
    """Physical field values (DBC units) of one output PGN; not-available fields all ones."""
    if name == "rudder":
        return {"Instance": 0, "DirectionOrder": 0, "Reserved1": 31, "AngleOrder": 3.2767,
                "Position": s.rudder_angle, "Reserved2": 65535}
    if name == "engine_rapid":
        return {"Instance": 0, "Speed": abs(s.shaft_rps) * 60.0, "BoostPressure": 6553500, "TiltTrim": 127,
                "Reserved": 65535}
    if name == "engine_dynamic":  # status fields explicitly 0: all ones would read as every alarm on
        return {"Instance": 0, "OilPressure": 6553500, "OilTemperature": 6553.5, "Temperature": 655.35,
                "AlternatorPotential": 327.67, "FuelRate": 3276.7, "TotalEngineHours": 4294967295,
                "CoolantPressure": 6553500, "FuelPressure": 65535000, "Reserved": 255, "Status1": 0,
                "Status2": 0, "Load": 127, "Torque": 127}
    if name == "heading":
        return {"SID": sid, "Heading": s.heading, "Deviation": 3.2767, "Variation": 3.2767, "Reference": 0,
                "Reserved": 63}
    if name == "attitude":  # yaw: the heading within +-pi; pitch bow up, roll starboard down, as the XDR's
        return {"SID": sid, "Yaw": math.remainder(s.heading, 2.0 * math.pi), "Pitch": s.pitch, "Roll": s.roll,
                "Reserved": 255}
    if name == "rate_of_turn":
        return {"SID": sid, "Rate": s.rate_of_turn, "Reserved": 16777215}
    if name == "position":  # no fix: both fields not available (0x7FFFFFFF)
        if not s.fix_valid:
            return {"Latitude": NOT_AVAILABLE_I32 * 1e-7, "Longitude": NOT_AVAILABLE_I32 * 1e-7}
        return {"Latitude": math.degrees(s.latitude), "Longitude": math.degrees(s.longitude)}
    cog, sog = (s.course_over_ground, s.speed_over_ground) if s.fix_valid else (6.5535, 655.35)  # 0xFFFF: n/a
    return {"SID": sid, "CogReference": 0, "Reserved1": 63, "Cog": cog, "Sog": sog, "Reserved2": 65535}


SERIAL_INTERFACES = frozenset({"slcan", "serial", "robotell", "seeedstudio"})  # python-can over a serial line
SEND_QUEUE = 256  # frames a serial-line bus's writer may hold; beyond this a frame is dropped (send_failed)
RECEIVE_QUEUE = 4096  # frames a serial-line bus's reader may hold for the loop; beyond, one is dropped (rx_overflow)
SERIAL_READ_WAIT = 0.05  # s: a serial-line bus's port timeout, and the longest its reader waits in one receive


class _Bus:
    """An open bus. Over a serial line (``SERIAL_INTERFACES``) python-can's receive waits up to
    the port's timeout even when asked not to wait (slcan's default 1 ms, serial's and
    seeedstudio's 100 ms), and its send writes the port and drains it, which waits for as long
    as the far end does not read: there a ``QueuedReader`` receives the frames and a
    ``QueuedWriter`` sends them and, last, shuts the bus down once the reader has stopped; the
    loop only takes and queues frames (a full queue drops the frame). Other interfaces receive
    and send at once."""

    def __init__(self, bus: can.BusABC, threaded: bool, name: str) -> None:
        self.bus = bus
        self._reader = QueuedReader(lambda: bus.recv(timeout=SERIAL_READ_WAIT), f"can-read-{name}",
                                    RECEIVE_QUEUE) if threaded else None
        self._writer = QueuedWriter(lambda msg: bus.send(_line_clock(msg), timeout=0.1), self._shut_down,
                                    (can.CanError, OSError), f"can-send-{name}", SEND_QUEUE) if threaded else None
        self._dropped = 0  # frames the reader dropped, as counted so far

    def _shut_down(self) -> None:
        """Shut the bus down once the reader has stopped (on the writer's thread)."""
        self._reader.close(wait=2.0 * SERIAL_READ_WAIT + 1.0)
        self.bus.shutdown()

    def receive(self, limit: int) -> Iterator[can.Message]:
        """Frames received since the last call, up to ``limit``, without waiting, each as it
        is read. Raises what python-can raised (over a serial line: what ended the reader)."""
        if self._reader is not None:
            for exc in self._reader.failures():
                raise exc
            yield from self._reader.take(limit)
            return
        for _ in range(limit):
            if (msg := self.bus.recv(timeout=0.0)) is None:
                return
            yield msg

    def newly_dropped(self) -> int:
        """Frames the reader dropped since the last call, its queue full."""
        if self._reader is None:
            return 0
        dropped, self._dropped = self._reader.dropped - self._dropped, self._reader.dropped
        return dropped

    def send(self, msg: can.Message) -> bool:
        """Send ``msg`` (or queue it for the writer); False if the queue is full. Raises
        can.CanOperationError where python-can could not send it at once."""
        if self._writer is None:
            self.bus.send(msg, timeout=0.0)
            return True
        return self._writer.put(msg)

    def flush(self) -> None:
        """Hand the queued frames to the writer (over a serial line)."""
        if self._writer is not None:
            self._writer.flush()

    def failures(self) -> list[Exception]:
        """The writer's send errors since the last call."""
        return [] if self._writer is None else self._writer.failures()

    def close(self) -> None:
        """Shut the bus down (over a serial line: have the writer do it, without waiting)."""
        if self._writer is None:
            self.bus.shutdown()
        else:
            self._reader.close()
            self._writer.close()


def _line_clock(msg: can.Message) -> can.Message:
    """The frame with its timestamp (Unix s) as a serial line's device clock: 32-bit
    milliseconds, which python-can's 'serial' adapter puts on the line (a Unix time in ms
    overflows it: ValueError, which stopped the writer at its first frame)."""
    ms = int(msg.timestamp * 1000.0) % 2**32
    return can.Message(timestamp=ms / 1000.0, arbitration_id=msg.arbitration_id, data=msg.data,
                       is_extended_id=msg.is_extended_id, is_rx=False)


class CanLink(Link):
    """Any python-can interface; the console's frames from the DBC of the settings."""

    open_errors = (can.CanError, OSError, ValueError, ImportError)
    lost_errors = (can.CanError, OSError)
    lost_kind = "bus_lost"

    def __init__(self, settings: CanLinkSettings) -> None:
        super().__init__(settings)
        self.console = load_dbc(dbc_path(settings.dbc))
        self.n2k = load_dbc(N2K_DBC)
        self._schedule = RateSchedule(settings.output_rates())
        self._allowed = None if settings.allowed_sources == "any" else frozenset(settings.allowed_sources)
        self._sid = 0
        self._fast_seq: dict[int, int] = {}
        received = {(m.frame_id >> 8) & 0x3FFFF for m in self.console.messages}
        self.network = NetworkManager(settings.n2k_name, settings.source_address, settings.n2k_product,
                                      settings.heartbeat_s, [pgn for _, pgn, _ in OUTPUTS.values()],
                                      received | ({RUDDER_PGN} if settings.rudder_order_pgn else set()))

    def _open_device(self) -> _Bus:
        s = self.settings
        try:
            serial_line = s.interface in SERIAL_INTERFACES
            bus = can.Bus(interface=s.interface, channel=s.channel, bitrate=s.bitrate,
                          **({"timeout": SERIAL_READ_WAIT} if serial_line else {}))
        except self.open_errors:
            raise
        except Exception as exc:  # a driver python-can cannot load fails in its own ways (NameError: kvaser)
            raise can.CanInitializationError(f"python-can cannot start interface {s.interface!r}: "
                                             f"{type(exc).__name__}: {exc}") from exc
        self.network.restart()  # a new bus: claim the address again
        return _Bus(bus, serial_line, self.name)

    def _close_device(self, bus: _Bus) -> None:
        bus.close()

    def _poll_device(self, now: float) -> Iterator[ControlInput]:
        for exc in self.device.failures():  # frames the writer could not send
            if not isinstance(exc, can.CanOperationError):
                raise exc
            self._count_error("send_failed")
        self._transmit(self.network.tick(now))
        self._count_error("rx_overflow", self.device.newly_dropped())
        for msg in self.device.receive(MAX_FRAMES_PER_POLL):
            self._report("rx", msg, msg.timestamp)
            yield from self._decode(msg, now)

    def _decode(self, msg: can.Message, now: float) -> list[ControlInput]:
        """Orders in one frame; errors counted, never raised."""
        if msg.is_error_frame:
            self._count_error("error_frame")
            return []
        if not msg.is_extended_id:
            self._count_error("unknown_frame")
            return []
        if msg.is_fd or len(msg.data) > 8:  # consoles and NMEA 2000 speak classic CAN
            self._count_error("fd_frame")
            return []
        _, pgn, source, destination = parse_identifier(msg.arbitration_id)
        if pgn in NETWORK_PGNS:  # address claims and ISO requests, from any device
            answer = self.network.on_frame(pgn, source, destination, bytes(msg.data), now)
            if answer is None:
                self._count_error("wrong_dlc")
            else:
                self._transmit(answer)
            return []
        if source == self.network.address:  # our own address: a device that has not claimed it, or an echo
            self._count_error("own_address")
            return []
        if self._allowed is not None and source not in self._allowed:
            self._count_error("source_not_allowed")
            return []
        try:
            spec = self.console.get_message_by_frame_id(msg.arbitration_id)
        except KeyError:
            spec = None
        try:
            if spec is not None:
                return self._console_orders(spec, msg, now)
            if pgn == RUDDER_PGN and self.settings.rudder_order_pgn:
                return self._rudder_pgn(msg, now)
        except cantools.database.errors.DecodeError:
            self._count_error("bad_frame")
            return []
        self._count_error("unknown_frame")
        return []

    def _in_range(self, spec, values: dict) -> bool:
        for sig in spec.signals:
            v = values.get(sig.name)
            if v is None or not math.isfinite(v) or (sig.minimum is not None and v < sig.minimum - 1e-9) or \
                    (sig.maximum is not None and v > sig.maximum + 1e-9):
                self._count_error("out_of_range")
                return False
        return True

    def _console_orders(self, spec, msg: can.Message, now: float) -> list[ControlInput]:
        if msg.dlc < spec.length:
            self._count_error("wrong_dlc")
            return []
        values = spec.decode(bytes(msg.data), decode_choices=False)
        if not self._in_range(spec, values):
            return []
        if spec.name == "HelmOrder":
            if values["Status"] != 1:
                self._count_error("invalid_status")
                return []
            return [ControlInput(now, self.name, OrderKind.RUDDER, math.radians(values["RudderOrder"]))]
        if spec.name == "EngineOrder":
            engine = int(values["Engine"])
            if values["Mode"] == 1:
                code = f"{int(values['TelegraphPosition']):02d}"
                if code not in ETL_POSITIONS:
                    self._count_error("out_of_range")
                    return []
                return [ControlInput(now, self.name, OrderKind.TELEGRAPH, ETL_POSITIONS[code], engine)]
            return [ControlInput(now, self.name, OrderKind.LEVER, float(values["Lever"]), engine)]
        if spec.name == "SearchlightOrder":
            order = searchlight_order(int(values["Light"]), values["Lamp"] == 1, values["Bearing"], values["Elevation"])
            if isinstance(order, str):
                self._count_error(order)
                return []
            return [ControlInput(now, self.name, OrderKind.SEARCHLIGHT, order)]
        self._count_error("unknown_frame")
        return []

    def _rudder_pgn(self, msg: can.Message, now: float) -> list[ControlInput]:
        spec = self.n2k.get_message_by_name("Rudder")
        if msg.dlc != spec.length:
            self._count_error("wrong_dlc")
            return []
        raw = spec.decode(bytes(msg.data), decode_choices=False, scaling=False)
        if raw["AngleOrder"] == 0x7FFF:
            self._count_error("not_available")
            return []
        angle = raw["AngleOrder"] * 1e-4
        if abs(angle) > math.pi / 2:
            self._count_error("out_of_range")
            return []
        return [ControlInput(now, self.name, OrderKind.RUDDER, angle)]

    def publish(self, state: ShipOutputs, now: float) -> None:
        if self.device is None or not self.network.can_send:
            return
        due = self._schedule.due(now)
        if due:
            self._sid = (self._sid + 1) % 253
        frames = []
        for name in due:
            message, pgn, priority = OUTPUTS[name]
            payload = self.n2k.get_message_by_name(message).encode(_n2k_fields(name, state, self._sid), strict=False)
            frames.append(Frame(priority, pgn, self.network.address, GLOBAL_ADDRESS, payload))
        try:
            self._transmit(frames)
        except self.lost_errors:
            self._lost(now)

    def _transmit(self, frames: list[Frame]) -> None:
        """Send PGNs (fast packet for the PGNs defined so); raises one of ``lost_errors`` if
        the bus was lost. A node that cannot claim an address reports itself down, once."""
        if self.network.state == "cannot_claim" and self._health.connected:
            self._health.connected = False
            self._failed = True
            self._count_error("cannot_claim")
        if self.device is None:
            return
        for f in frames:
            if f.pgn in FAST_PGNS:
                seq = self._fast_seq.get(f.pgn, -1) + 1
                self._fast_seq[f.pgn] = seq % 8
                datas = fast_packet_frames(f.payload, seq)
            else:
                datas = [f.payload]
            can_id = identifier(f.priority, f.pgn, f.source, f.destination)
            for data in datas:
                self._send(can.Message(timestamp=time.time(), arbitration_id=can_id, data=data, is_extended_id=True,
                                       is_rx=False))
        self.device.flush()  # the frames of one call reach the writer together

    def _send(self, msg: can.Message) -> None:
        """Send one frame; a full transmit buffer (or writer's queue) drops it (counted), the
        next cycle follows."""
        try:
            sent = self.device.send(msg)
        except can.CanOperationError:
            sent = False
        if not sent:
            self._count_error("send_failed")
            return
        self._health.outputs += 1
        self._report("tx", msg, msg.timestamp)
