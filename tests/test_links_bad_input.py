"""Bad input never crashes a parser: random bytes, truncated and corrupted sentences, wrong
DLC, out-of-range registers. Every case is either a valid order or a counted error kind."""
import math
import time

import can
from conftest import fuzz_budget
from hypothesis import example, given, settings
from hypothesis import strategies as st

from bridge_node.links.messages import ControlInput
from bridge_node.links.can.link import CanLink
from bridge_node.links.modbus.link import register_order
from bridge_node.links.can.n2k_frames import fast_packet_frames, identifier, parse_identifier
from bridge_node.links.can.n2k_network import ADDRESS_CLAIM, NETWORK_PGNS
from bridge_node.links.nmea0183.sentences import ETL, PRC, ROR, SentenceError, parse_order
from bridge_node.links.can.settings import CanLinkSettings
from bridge_node.links.modbus.settings import RegisterSpec
from sim_core.ship.orders import OrderKind

ORDERS = [str(ROR("RC", "ROR", ("-22.0", "A", "34.0", "A", "B"))),
          str(ETL("RC", "ETL", ("120000.00", "O", "14", "30", "B", "1"))),
          str(PRC("RC", "PRC", ("-25.0", "A", "", "V", "-45.1", "P", "B", "2")))]


def outcome(line: str):
    try:
        out = parse_order(line, 0.0, "test")
    except SentenceError as exc:
        return exc.kind
    assert all(isinstance(o, ControlInput) for o in out)
    for o in out:
        assert o.kind != "rudder" or (math.isfinite(o.value) and abs(o.value) <= math.pi / 2)
        assert o.kind != "lever" or (math.isfinite(o.value) and abs(o.value) <= 100.0)
    return out


@settings(max_examples=fuzz_budget(3000), deadline=None)
@given(st.text(max_size=120))
def test_random_text_is_an_order_or_a_counted_error(text):
    outcome(text)


@settings(max_examples=fuzz_budget(2000), deadline=None)
@given(st.binary(max_size=100))
def test_random_bytes_as_received_never_crash(data):
    outcome(data.decode("ascii", errors="replace"))


@settings(max_examples=fuzz_budget(2000), deadline=None)
@given(st.sampled_from(ORDERS), st.integers(0, 80), st.integers(0, 80), st.characters())
def test_truncated_or_corrupted_orders_are_rejected(line, cut, where, char):
    truncated = line[:cut]
    if truncated != line:
        assert isinstance(outcome(truncated), str)
    i = where % len(line)
    corrupted = line[:i] + char + line[i + 1:]
    if corrupted != line:
        result = outcome(corrupted)
        # a changed character either breaks the checksum or the form; it never yields an order
        # unless it was a change the checksum cannot see (the checksum digits themselves case-folded)
        assert isinstance(result, str) or corrupted.upper() == line.upper()


@settings(max_examples=fuzz_budget(300), deadline=None)
@given(st.sampled_from(["-nan", "nan", "inf", "1e400", "-1e400"]))
def test_nan_and_infinite_fields_are_rejected(value):
    assert outcome(str(ROR("RC", "ROR", (value, "A", "", "V", "B")))) in ("bad_field", "out_of_range")


def fresh_can_link() -> CanLink:
    """A new, unopened CAN link: its error counts start at zero in every example."""
    return CanLink(CanLinkSettings(type="can", name="fuzz", channel="icebridge-fuzz", allowed_sources="any"))


def answered_network_frame(msg: can.Message) -> bool:
    """A well-formed address claim or ISO request: the link answers it; no order, no error."""
    if msg.is_error_frame or not msg.is_extended_id or msg.is_fd or len(msg.data) > 8:
        return False
    pgn = parse_identifier(msg.arbitration_id)[1]
    return pgn in NETWORK_PGNS and len(msg.data) >= (8 if pgn == ADDRESS_CLAIM else 3)


def decoded_or_one_error(msg: can.Message) -> list[ControlInput]:
    """Decode one frame on a fresh link: valid orders, or none and exactly one counted error,
    or none and no error for a network-management frame the link answers."""
    link = fresh_can_link()
    out = link._decode(msg, time.monotonic())
    errors = sum(link.health().errors.values())
    if answered_network_frame(msg):
        assert out == [] and errors == 0
        return out
    assert errors == (0 if out else 1)
    for o in out:
        assert o.kind in (OrderKind.RUDDER, OrderKind.TELEGRAPH, OrderKind.LEVER)
        assert isinstance(o.value, str) or math.isfinite(o.value)
        assert o.kind != OrderKind.RUDDER or abs(o.value) <= math.pi / 2
        assert o.kind != OrderKind.LEVER or abs(o.value) <= 100.0
    return out


@settings(max_examples=fuzz_budget(3000), deadline=None)
@given(st.integers(0, 0x1FFFFFFF), st.binary(max_size=8), st.booleans(), st.booleans())
@example(0xEA0000, b"\x00\x00\x00", True, False)  # an ISO request: answered, neither order nor error
def test_random_can_frames_are_orders_or_counted(can_id, data, extended, error_frame):
    decoded_or_one_error(can.Message(arbitration_id=can_id if extended else can_id & 0x7FF, data=data,
                                     is_extended_id=extended, is_error_frame=error_frame))


@settings(max_examples=fuzz_budget(2000), deadline=None)
@given(st.sampled_from([0xFF50, 0xFF51, 127245]), st.binary(max_size=8), st.integers(0, 0xFF))
def test_console_pgns_with_any_payload_are_orders_or_counted(pgn, data, source):
    decoded_or_one_error(can.Message(arbitration_id=identifier(6, pgn, source), data=data, is_extended_id=True))


@settings(max_examples=fuzz_budget(2000), deadline=None)
@given(st.integers(0, 0xFFFF), st.sampled_from(["rudder", "lever", "telegraph"]), st.sampled_from(["int16", "uint16"]),
       st.floats(1e-6, 10) | st.floats(-10, -1e-6))  # every scale the config allows, in that range
def test_any_register_value_is_an_order_or_an_error_kind(raw, order, kind, scale):
    spec = RegisterSpec(order=order, address=0, type=kind, scale=scale)
    out = register_order(spec, raw, 0.0, "io")
    assert out in ("out_of_range", "bad_field") or isinstance(out, ControlInput)


@settings(max_examples=fuzz_budget(500), deadline=None)
@given(st.binary(min_size=9, max_size=223), st.integers(0, 7))
def test_fast_packet_frames_carry_the_payload(payload, seq):
    frames = fast_packet_frames(payload, seq)
    assert all(len(f) == 8 and f[0] >> 5 == seq for f in frames)
    assert [f[0] & 0x1F for f in frames] == list(range(len(frames)))
    assert (frames[0][2:] + b"".join(f[1:] for f in frames[1:]))[:len(payload)] == payload
    assert frames[0][1] == len(payload)
