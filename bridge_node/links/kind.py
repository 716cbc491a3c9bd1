"""A link kind: everything one protocol brings to the node, in one place, registered once.

A protocol's module declares its settings model (a ``LinkSettingsBase`` with ``type`` the
kind's name), its ``Link`` class, how its traffic is written to and read back from the
session record (``RecordFormat``), and how a replay feeds recorded inputs back to its own
link code (``ReplayFeed``), and calls ``register_kind`` once. The node's config, the session
record, the tick log, the config reference and the session replay all look kinds up here, so
adding a link kind touches its own module and ``links.registry`` (which imports the kinds),
nothing else. The software console's end of a link (the HIL bench's peer) lives with the
bench, in ``hil.console_registry``: the links never import the bench.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, GetCoreSchemaHandler, create_model
from pydantic_core import PydanticCustomError, core_schema

from bridge_node.links.base import Link
from bridge_node.links.messages import Traffic
from bridge_node.links.settings import LinkSettingsBase


class RecordWriter(ABC):
    """Appends one link kind's traffic to its file of the session record."""

    @abstractmethod
    def write(self, traffic: Traffic) -> None:
        """One frame, sentence, register access or PDU, as a complete line."""

    @abstractmethod
    def flush(self) -> None:
        """Hand what is buffered to the OS."""

    @abstractmethod
    def close(self) -> None:
        """Flush and close the file."""


class TextLineWriter(RecordWriter):
    """A text file of one line per traffic item, made by ``line_of`` (without its newline)."""

    def __init__(self, path: Path, line_of: Callable[[Traffic], str], encoding: str = "ascii") -> None:
        self._file = open(path, "a", encoding=encoding, errors="replace")
        self._line_of = line_of

    def write(self, traffic: Traffic) -> None:
        self._file.write(self._line_of(traffic) + "\n")

    def flush(self) -> None:
        self._file.flush()

    def close(self) -> None:
        self._file.close()


@dataclass(frozen=True)
class RecordFormat:
    """A link kind's file in the session record.

    ``writer`` opens the file for appending; ``read`` gives its records in file order and
    counts of torn and malformed lines; ``direction`` and ``unix_time`` read a record's
    direction ("rx", "tx", "read", ...) and time (s). A record whose direction is
    ``input_direction`` is an input the tick log counts and a replay feeds back; None: the
    kind's inputs are not replayed (DIS: other simulators' entities, replayed as traffic)."""

    file: str
    writer: Callable[[Path], RecordWriter]
    read: Callable[[Path], tuple[list, Counter]]
    direction: Callable[[Any], str]
    unix_time: Callable[[Any], float]
    input_direction: str | None

    def is_input(self, record: object) -> bool:
        return self.input_direction is not None and self.direction(record) == self.input_direction


class ReplayFeed(ABC):
    """One recorded link given back its inputs: ``link`` is the node's own link code on an
    in-process device (a ``loop://`` port, a virtual bus, a list), fed tick by tick."""

    link: Link

    @abstractmethod
    def owns(self, record: object) -> bool:
        """Whether a recorded input of this kind was read by this link."""

    @abstractmethod
    def feed(self, record: object, tick_monotonic: float, tick_unix: float) -> None:
        """Give the link one recorded input of the tick that polled at ``tick_monotonic``
        (the clock the links ran on, s) and ``tick_unix`` (wall clock, s)."""

    def after_poll(self) -> None:
        """Called after each tick's poll (default: nothing)."""

    def close(self) -> None:
        """Release what the feed holds besides its link (default: nothing)."""


@dataclass(frozen=True)
class LinkKind:
    """One protocol: its ``type`` name, settings model, link class, session-record format and,
    where its inputs are replayed, ``replay(settings, siblings)``: a feed for one link given
    the settings of every link of the kind in the config."""

    name: str
    settings: type[LinkSettingsBase]
    link: type[Link]
    record: RecordFormat
    replay: Callable[[LinkSettingsBase, Sequence[LinkSettingsBase]], ReplayFeed] | None = None


LINK_KINDS: dict[str, LinkKind] = {}  # settings ``type`` -> kind, in registration order


def register_kind(kind: LinkKind) -> LinkKind:
    """Add a link kind; ValueError if its name is taken or its settings' ``type`` differs."""
    if kind.name in LINK_KINDS:
        raise ValueError(f"link kind {kind.name!r} is registered twice")
    literal = kind.settings.model_fields["type"].annotation
    if getattr(literal, "__args__", None) != (kind.name,):
        raise ValueError(f"{kind.settings.__name__}.type must be Literal[{kind.name!r}]")
    LINK_KINDS[kind.name] = kind
    return kind


def link_kind(name: str) -> LinkKind:
    """The kind registered as ``name``; ValueError listing the known kinds."""
    try:
        return LINK_KINDS[name]
    except KeyError:
        raise ValueError(f"no link type {name!r}; known: {', '.join(LINK_KINDS)}") from None


class OneOfTheKinds:
    """Pydantic annotation of a ``[[links]]`` table: validated by the model of its ``type``'s
    registered kind, looked up when the table is read (so a kind registered later, a test's
    say, is taken too); errors keep their key (``links.0.port``). ``models()`` gives the
    config reference every kind's model."""

    def __get_pydantic_core_schema__(self, source: type, handler: GetCoreSchemaHandler) -> core_schema.CoreSchema:
        return core_schema.no_info_plain_validator_function(
            self._validate, serialization=core_schema.plain_serializer_function_ser_schema(
                lambda v, info: v.model_dump(mode=info.mode, by_alias=info.by_alias, exclude_unset=info.exclude_unset,
                                             exclude_defaults=info.exclude_defaults, exclude_none=info.exclude_none),
                info_arg=True))

    @staticmethod
    def _validate(value: object) -> LinkSettingsBase:
        if isinstance(value, LinkSettingsBase):
            return value
        if not isinstance(value, dict):
            raise PydanticCustomError("link_table", "a link must be a table with a type")
        if not isinstance(value.get("type"), str) or value["type"] not in LINK_KINDS:  # refused as a Literal of the known kinds: the error keys ``type``
            known = create_model("LinkType", type=(Literal[tuple(LINK_KINDS)], ...))
            known.model_validate({k: v for k, v in value.items() if k == "type"})
        return LINK_KINDS[value["type"]].settings.model_validate(value)

    @staticmethod
    def models() -> list[type[BaseModel]]:
        return [kind.settings for kind in LINK_KINDS.values()]
