"""The bridge interfaces as tables, from the links' own definitions: the NMEA 0183 sentences
sent and the orders read, the NMEA 2000 PGNs sent with their DBC signals, the console's CAN
frames, and the Modbus register orders and indicators."""
from __future__ import annotations

import typing

import cantools

from bridge_node.links.can.link import OUTPUTS, dbc_path, load_dbc
from bridge_node.links.nmea0183.sentences import (
    COMMON_ORDER_TALKERS,
    DEFAULT_RATES,
    DEFAULT_TALKERS,
    ORDER_SENTENCES,
    SEARCHLIGHT_SENTENCE,
)
from bridge_node.links.can.settings import CanLinkSettings
from bridge_node.links.modbus.settings import RegisterSpec, WriteSpec


def _signals(message: cantools.database.can.Message) -> list[str]:
    rows = []
    for s in message.signals:
        span = f"{s.minimum}..{s.maximum}" if s.minimum is not None else ""
        rows.append(f"| `{s.name}` | {s.start} | {s.length} | {s.scale} | {s.unit or ''} | {span} |")
    return ["| signal | start bit | bits | scale | unit | range |", "|---|---|---|---|---|---|", *rows, ""]


def nmea0183_section() -> list[str]:
    lines = ["## NMEA 0183", "", "Sentences sent to the instruments (default talker and rate; "
             "`[[links]] talkers` and `rates` change them):", "", "| sentence | talker | rate, Hz |", "|---|---|---|"]
    lines += [f"| `{name}` | `{talker}` | {DEFAULT_RATES.get(name, 0)} |" for name, talker in DEFAULT_TALKERS.items()]
    lines += ["", f"Orders read: {', '.join(f'`{s}`' for s in sorted(ORDER_SENTENCES))} from the talkers "
              f"{', '.join(f'`{t}`' for t in COMMON_ORDER_TALKERS)} (by default), and the searchlight's "
              f"proprietary `${SEARCHLIGHT_SENTENCE}`.", ""]
    return lines


def nmea2000_section() -> list[str]:
    db = load_dbc(dbc_path("nmea2000.dbc"))
    lines = ["## NMEA 2000 (CAN)", "", "PGNs sent (`config/nmea2000.dbc`):", "",
             "| output | DBC message | PGN | priority |", "|---|---|---|---|"]
    lines += [f"| `{name}` | `{message}` | {pgn} | {priority} |" for name, (message, pgn, priority) in OUTPUTS.items()]
    lines.append("")
    for name, (message, pgn, _) in OUTPUTS.items():
        lines += [f"### `{message}` (PGN {pgn})", "", *_signals(db.get_message_by_name(message))]
    console_dbc = CanLinkSettings.model_fields["dbc"].default
    console = load_dbc(dbc_path(console_dbc))
    lines += [f"## Console CAN frames (`config/{console_dbc}`)", ""]
    for message in console.messages:
        lines += [f"### `{message.name}` (frame id 0x{message.frame_id:X})", "", *_signals(message)]
    return lines


def modbus_section() -> list[str]:
    orders = typing.get_args(RegisterSpec.model_fields["order"].annotation)
    values = typing.get_args(WriteSpec.model_fields["value"].annotation)
    return ["## Modbus", "", "A console's input or holding registers the node reads as orders "
            "(`[[links.registers]] order`): " + ", ".join(f"`{o}`" for o in orders) + ".", "",
            "Indicator values the node writes to holding registers after each poll "
            "(`[[links.writes]] value`): " + ", ".join(f"`{v}`" for v in values) + ".", "",
            "Each register's type (`int16`, `uint16`), scale and address are in the config "
            "reference.", ""]


def interfaces_reference() -> str:
    """The Markdown page of the bridge interfaces."""
    return "\n".join(["# Bridge interfaces", "", "Made from the links' own tables when the site is built.", "",
                      *nmea0183_section(), *nmea2000_section(), *modbus_section()])
