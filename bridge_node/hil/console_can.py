"""The software console's CAN end: the console's own frames (console.dbc) or an NMEA 2000
helm's PGN 127245 out, the node's NMEA 2000 PGNs read back as instrument readings."""
from __future__ import annotations

import math
import random

import can

from bridge_node.hil.console_links import ETL_CODES, ConsoleLink, Order, Reading
from bridge_node.hil.settings import CanConsoleSettings
from bridge_node.links.can.link import N2K_DBC, dbc_path, load_dbc
from bridge_node.links.can.n2k_frames import identifier, parse_identifier
from sim_core.ship.orders import OrderKind

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
