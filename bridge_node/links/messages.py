"""What the links and the node exchange: the console's orders (``ControlInput``, one value
type per kind), the alarms the node raises, other vessels, a link's health, and raw traffic
for ``Listener`` objects (the session record is one), as python-can hands ``Message`` objects
to its listeners."""
from __future__ import annotations

import errno
import math
from abc import ABC, abstractmethod
from collections import Counter
from dataclasses import dataclass, field

from sim_core.ship.orders import OrderKind
from sim_core.ship.searchlights import MAX_SEARCHLIGHTS, SearchlightOrder

# the one value type of each kind of order
ORDER_VALUES: dict[OrderKind, type] = {OrderKind.RUDDER: float, OrderKind.TELEGRAPH: str, OrderKind.LEVER: float,
                                       OrderKind.SEARCHLIGHT: SearchlightOrder}
RUDDER_ORDER_LIMIT_DEG = 90.0  # beyond this a rudder order is nonsense, not an order to clamp
ALARM_TEXT_MAX = 52  # characters: what an ALR sentence's text field holds within NMEA 0183's 82
# ETL position codes (IEC 61162-1; also the console's CAN and Modbus codes) -> telegraph positions
ETL_POSITIONS = {
    "00": "stop", "01": "dead_slow_ahead", "02": "slow_ahead", "03": "half_ahead", "04": "full_ahead",
    "05": "navigation_full_ahead", "11": "dead_slow_astern", "12": "slow_astern", "13": "half_astern",
    "14": "full_astern", "15": "crash_astern",
}


def searchlight_order(index: int, on: bool | None, bearing_deg: float | None,
                      elevation_deg: float | None) -> SearchlightOrder | str:
    """A console's searchlight order (light 0..3; bearing deg from the bow, + starboard,
    within +-180; elevation deg, + up, within +-90; None: unchanged) in rad, or the error
    kind it is counted as. The light's own train and tilt limits are the world's to check."""
    angles = [(v, limit) for v, limit in ((bearing_deg, 180.0), (elevation_deg, 90.0)) if v is not None]
    if any(not math.isfinite(v) for v, _ in angles):
        return "bad_field"
    if not 0 <= index < MAX_SEARCHLIGHTS or any(abs(v) > limit for v, limit in angles):
        return "out_of_range"
    return SearchlightOrder(index, on, *(None if v is None else math.radians(v) for v in (bearing_deg, elevation_deg)))


@dataclass(frozen=True)
class ControlInput:
    """One order from the console, typed: its ``kind`` and a ``value`` of that kind's one
    type (``ORDER_VALUES``): rudder rad (+ starboard), lever percent (-100..100), a
    telegraph position name, or a ``SearchlightOrder``. ``time`` is the node's monotonic
    clock, s. TypeError for a value of another type (a link's decoding bug, not bad input:
    the links count bad input before they make an order)."""

    time: float
    source: str  # link name
    kind: OrderKind
    value: float | str | SearchlightOrder
    engine: int = 0  # 0 centre, odd starboard, even port (NMEA convention)

    def __post_init__(self) -> None:
        kind = OrderKind(self.kind)
        object.__setattr__(self, "kind", kind)
        if isinstance(self.value, int) and not isinstance(self.value, bool) and ORDER_VALUES[kind] is float:
            object.__setattr__(self, "value", float(self.value))
        if not isinstance(self.value, ORDER_VALUES[kind]):
            raise TypeError(f"a {kind} order's value is a {ORDER_VALUES[kind].__name__}, not {self.value!r}")


@dataclass(frozen=True)
class Alarm:
    """An alarm the node raises: id number, text, and whether it is active now. Texts are
    written to fit ALR whole (at most ``ALARM_TEXT_MAX`` characters, no commas): never cut."""

    number: int
    text: str
    active: bool

    def __post_init__(self) -> None:
        if len(self.text) > ALARM_TEXT_MAX or any(c in self.text for c in ",*$!"):
            raise ValueError(f"alarm text {self.text!r}: at most {ALARM_TEXT_MAX} characters, no , * $ !")


@dataclass(frozen=True)
class Vessel:
    """Another vessel the node knows of (one a DIS simulator sends, say), SI: rad, m/s, m.
    ``time`` is the node's monotonic clock when it was last heard of, s; dimensions 0 are
    unknown."""

    key: str  # unique among the vessels: the source and its own id
    mmsi: int
    name: str
    time: float
    latitude: float
    longitude: float
    heading: float  # true, [0, 2 pi)
    course_over_ground: float
    speed_over_ground: float
    rate_of_turn: float  # + to starboard
    length: float = 0.0
    beam: float = 0.0
    fix_valid: bool = True  # another vessel is placed only where its position is known


@dataclass
class LinkHealth:
    """What a link reports about itself; ``Link.health()`` hands out a copy."""

    name: str
    connected: bool = False
    inputs: int = 0
    outputs: int = 0
    reconnects: int = 0
    opening: bool = False  # the device is being opened on the worker thread
    errors: Counter = field(default_factory=Counter)  # kind -> count
    last_error: str = ""  # why the device last failed, in the OS's or the library's own words
    fault: str | None = None  # the instructor's fault on the link (``bridge_node.links.faults``), if any

    def as_dict(self) -> dict:
        return {"name": self.name, "connected": self.connected, "inputs": self.inputs, "outputs": self.outputs,
                "reconnects": self.reconnects, "opening": self.opening, "errors": dict(self.errors),
                "last_error": self.last_error, "fault": self.fault}


def device_error_texts(exc: BaseException) -> tuple[str, list[str]]:
    """Why a device failed: the whole message (for the log), and short forms for an alarm,
    best first: the innermost OS error's own text (``strerror``), its errno name, the message."""
    full = str(exc) or type(exc).__name__
    short, inner = [], exc
    while inner is not None:
        if isinstance(inner, OSError) and inner.errno in errno.errorcode:
            short = [inner.strerror or "", errno.errorcode[inner.errno]]
        inner = inner.__cause__ or inner.__context__
    return full, [s for s in short if s] + [full]


@dataclass(frozen=True)
class Traffic:
    """Raw traffic of one link as it went over the wire: a ``can.Message``, an NMEA sentence
    (str without CR LF), a Modbus ``RegisterAccess``, or a DIS PDU (bytes)."""

    unix_time: float  # wall clock, s
    link: str  # link name
    protocol: str  # the link's registry key: "can", "nmea0183", "modbus", "dis"
    direction: str  # "rx" / "tx"; Modbus: "read" / "write"
    data: object


class Listener(ABC):
    """Receives the raw traffic of the links it is added to, like python-can's ``Listener``.
    Called on the loop's thread; ``flush`` once per tick, ``stop`` when the hub closes."""

    @abstractmethod
    def on_traffic(self, traffic: Traffic) -> None:
        """One frame, sentence or register access in or out."""

    def flush(self) -> None:
        """Called once per tick (default: nothing)."""

    def stop(self) -> None:
        """Release what the listener holds (default: nothing)."""
