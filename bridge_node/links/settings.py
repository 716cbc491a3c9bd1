"""What every link's settings share (``LinkSettingsBase``: each kind's model, in the kind's
own module, adds ``type`` and its keys) and the order arbitration (``[arbitration]``).
Validated by pydantic: every error names the key."""
from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Literal, Self

from pydantic import Field

from sim_core.params import Params

NAME_MAX = 24  # characters: every alarm text naming a link then fits an ALR sentence
Name = Annotated[str, Field(min_length=1, max_length=NAME_MAX, pattern=r"^[A-Za-z0-9_\-]+$")]
BAUD_RATES = (4800, 9600, 19200, 38400, 57600, 115200)


class LinkSettingsBase(Params):
    """What every ``[[links]]`` table has; each link kind's settings add ``type`` (its
    name, a Literal) and their own keys."""

    name: Name
    timeout_s: float = Field(1.0, gt=0.05, le=60.0, description="a source silent this long is stale, s")
    engine: int = Field(0, ge=0, le=9, description="the engine number (0 centre or single, odd starboard, even "
                        "port) whose telegraph and lever orders are taken; others are counted as other_engine")

    def udp_destination(self) -> tuple[str, int] | None:
        """(host, port) this link alone sends its outputs to on UDP; None: none (default)."""
        return None

    def resources(self) -> list[str]:
        """What this link holds that no other link of the node may hold too (a CAN bus, a
        serial port, a server's device, a listening port), in words for an error; the UDP
        output's destination is ``udp_destination``. Default: nothing."""
        return []

    def with_files(self, resolve: Callable[[str, str], str]) -> Self:
        """These settings with the files they name found: ``resolve(key, value)`` gives a
        key's path relative to the config file's folder, else to ``config/``, checked
        (default: no file keys)."""
        return self


def known_keys(v: dict, allowed: dict, what: str) -> dict:
    """A table setting (`rates`, `talkers`) whose keys are all among `allowed`; ValueError naming the rest."""
    unknown = sorted(set(v) - set(allowed))
    if unknown:
        raise ValueError(f"unknown {what}(s) {unknown}; allowed: {', '.join(sorted(allowed))}")
    return v


class ArbitrationSettings(Params):
    """Which link's orders win (first fresh source in each list), and what happens when
    every source of an order has gone stale. Searchlight orders are not arbitrated: every
    one from a searchlight source is passed on, and a light holds its last order."""

    rudder: list[Name] = Field(default_factory=list, description="rudder order sources by priority")
    engine: list[Name] = Field(default_factory=list, description="engine order sources by priority")
    searchlight: list[Name] | None = Field(None, description="links whose searchlight orders are taken (each order "
                                           "as it comes; a light holds its last); unset: the rudder and engine sources")
    fail_safe: Literal["hold", "midships_stop"] = "midships_stop"
    fail_safe_after_s: float = Field(3.0, ge=0.0, le=600.0, description="after every source is stale, s")
