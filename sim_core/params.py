"""Base class for static parameter blocks (the 'model' half of model/data).

Parameter blocks are frozen pydantic models: validated once when built (from config or
code), immutable afterwards, so one block can be shared by every step without copying.
Types are strict: a number is a number (``thickness = true`` or ``"1.0"`` is an error, not
1.0 m), a flag is a boolean; integers are accepted where decimals are expected.
"""
from pydantic import BaseModel, ConfigDict


class Params(BaseModel):
    """Frozen, validated parameter block; unknown keys are errors (catches config typos)."""

    model_config = ConfigDict(frozen=True, extra="forbid", strict=True)


def repeated(names: list[str]) -> list[str]:
    """Names that occur more than once (sorted), for uniqueness checks in configs."""
    return sorted({n for n in names if names.count(n) > 1})
