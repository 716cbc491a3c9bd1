"""NMEA 2000 on CAN: 29-bit identifiers and fast-packet framing.

Field encoding is cantools' job (``config/nmea2000.dbc``). What no library here does for
sending is the J1939 identifier with a chosen priority and source, and NMEA 2000's
fast-packet split of payloads longer than 8 bytes, so those few lines are written here.
"""
from __future__ import annotations

FAST_PACKET_MAX = 223  # bytes


def identifier(priority: int, pgn: int, source: int, destination: int = 0xFF) -> int:
    """29-bit identifier: priority bits 28..26, PGN, source bits 7..0; for PDU1 PGNs
    (PF < 240) the PS byte carries the destination."""
    if (pgn >> 8) & 0xFF < 240:
        pgn = (pgn & 0x3FF00) | destination
    return ((priority & 0x7) << 26) | ((pgn & 0x3FFFF) << 8) | (source & 0xFF)


def parse_identifier(can_id: int) -> tuple[int, int, int, int]:
    """(priority, PGN, source, destination) of a 29-bit identifier; the destination is the
    PS byte of a PDU1 PGN (PF < 240), else 255 (all)."""
    pgn = (can_id >> 8) & 0x3FFFF
    destination = 0xFF
    if (pgn >> 8) & 0xFF < 240:
        pgn, destination = pgn & 0x3FF00, pgn & 0xFF
    return (can_id >> 26) & 0x7, pgn, can_id & 0xFF, destination


def fast_packet_frames(payload: bytes, sequence: int) -> list[bytes]:
    """Split a payload into fast-packet frames: frame 0 = [seq<<5 | 0, length, 6 bytes],
    then [seq<<5 | n, 7 bytes]; the last frame padded with 0xFF. A fast-packet PGN goes out
    so even when its payload is short."""
    if not 0 < len(payload) <= FAST_PACKET_MAX:
        raise ValueError(f"fast packet carries 1..{FAST_PACKET_MAX} bytes, got {len(payload)}")
    head = (sequence & 0x7) << 5
    frames = [bytes([head, len(payload)]) + payload[:6]]
    rest = payload[6:]
    for n, i in enumerate(range(0, len(rest), 7), start=1):
        frames.append(bytes([head | n]) + rest[i:i + 7])
    frames[-1] = frames[-1].ljust(8, b"\xff")
    return frames
