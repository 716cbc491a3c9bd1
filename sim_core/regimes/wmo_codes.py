"""WMO sea-ice codes of the egg code, as SIGRID-3 charts carry them.

Sources:
- WMO Sea-Ice Nomenclature, WMO-No. 259 (2014 edition), sections 1 (stages of development,
  with their thickness ranges) and 2 (forms of ice, with the floe-size ranges);
- SIGRID-3: A vector archive format for sea ice charts, JCOMM Technical Report No. 23
  (2004, rev. 2014), tables of the CT/CA/CB/CC, SA/SB/SC and FA/FB/FC codes (Appendix A,
  rev. 3.1: form of ice 01 pancake, 02 brash, 03 ice cake, 04 small floe ... 09 fast ice,
  10 growlers; WMO's S-411 converter renumbers these into S-411's own ICEFLZ values, one up);
- the conversion of concentration codes to tenths follows WMO's own S-411 converter
  (wmo-im/S-41X-PS, ``S-411/scripts/S411func.py``, ``Sig3_Conc``): a range becomes its mean,
  9+/10 (``91``) is 9.5.

The nomenclature gives thickness as a range (nilas: under 10 cm; thick first-year: over
120 cm; old ice: no upper bound). Where it is open, the bound used here is the one the
nomenclature's own description names ("up to 2 m" for first-year, "up to 2.5 m" for
second-year, "3 m or more" for multi-year), and the nominal thickness is the middle of
the range. Codes, names and ranges are a table no library carries, hence written here.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CodeRange:
    """A WMO code with its name and the range (min, max) of the quantity it stands for, m."""

    code: int
    name: str
    low: float
    high: float

    @property
    def nominal(self) -> float:
        """The middle of the range, m."""
        return 0.5 * (self.low + self.high)


# stage of development (SA/SB/SC): code, name, thickness range m (WMO-No. 259, 1.1-1.8)
STAGES: dict[int, CodeRange] = {c.code: c for c in [
    CodeRange(81, "new", 0.0, 0.10),
    CodeRange(82, "nilas", 0.0, 0.10),
    CodeRange(83, "young", 0.10, 0.30),
    CodeRange(84, "grey", 0.10, 0.15),
    CodeRange(85, "grey_white", 0.15, 0.30),
    CodeRange(86, "first_year", 0.30, 2.00),
    CodeRange(87, "thin_first_year", 0.30, 0.70),
    CodeRange(88, "thin_first_year_1", 0.30, 0.50),
    CodeRange(89, "thin_first_year_2", 0.50, 0.70),
    CodeRange(91, "medium_first_year", 0.70, 1.20),
    CodeRange(93, "thick_first_year", 1.20, 2.00),
    CodeRange(95, "old", 2.00, 3.00),
    CodeRange(96, "second_year", 2.00, 2.50),
    CodeRange(97, "multi_year", 2.50, 3.00),
]}

# form of ice (FA/FB/FC): code, name, size range across, m (WMO-No. 259, 2.1-2.4). Brash
# has no lower bound ("fragments not more than 2 m across"); 0.5 m stands for it here.
FLOE_SIZES: dict[int, CodeRange] = {c.code: c for c in [
    CodeRange(1, "pancake", 0.3, 3.0),
    CodeRange(2, "brash", 0.5, 2.0),
    CodeRange(3, "ice_cake", 2.0, 20.0),
    CodeRange(4, "small_floe", 20.0, 100.0),
    CodeRange(5, "medium_floe", 100.0, 500.0),
    CodeRange(6, "big_floe", 500.0, 2000.0),
    CodeRange(7, "vast_floe", 2000.0, 10000.0),
    CodeRange(8, "giant_floe", 10000.0, 50000.0),
    CodeRange(9, "fast_ice", 0.0, 0.0),
]}
FAST_ICE = 9
GIANT_FLOE = 8

# codes SIGRID-3 defines that the field cannot lay out, and why
UNSUPPORTED_STAGES = {98: "glacier ice is not sea ice", 99: "undetermined: the field needs a thickness"}
UNSUPPORTED_FLOES = {10: "growlers, floebergs and bergy bits are glacier ice",
                     99: "undetermined: the field needs a floe size"}
CONCENTRATION_NONE = {0: "ice free", 1: "open water (under 1/10)", 2: "bergy water", 98: "ice free"}


def concentration_tenths(code: int) -> float:
    """Concentration in tenths of a SIGRID-3 concentration code: ``10``-``90`` one digit of
    tenths, ``91`` 9+/10 (9.5), ``92`` 10/10, ``xy`` (x < y) the range x-y/10 as its mean,
    ``x1`` (x < 9) the range x/10 to 10/10 as its mean;
    ``00``, ``01``, ``02`` and ``98`` lay no ice (0). ValueError for any other code."""
    if code in CONCENTRATION_NONE:
        return 0.0
    if code == 91:
        return 9.5
    if code == 92:
        return 10.0
    tens, units = divmod(code, 10)
    if 1 <= tens <= 9 and units == 0:
        return float(tens)
    if 1 <= tens <= 8 and units == 1:  # x1: x/10 to 10/10, as S-411's converter reads it
        return 0.5 * (tens + 10)
    if 1 <= tens < units <= 9:
        return 0.5 * (tens + units)
    raise ValueError(f"{code:02d} is not a SIGRID-3 concentration code (10-92, a range such as 46, or 00/01/02/98)")


def stage(code: int) -> CodeRange:
    """The stage of development of a code; ValueError naming the allowed codes."""
    return _lookup(code, STAGES, UNSUPPORTED_STAGES, "stage of development")


def floe_size(code: int) -> CodeRange:
    """The form of ice (floe size) of a code; ValueError naming the allowed codes."""
    return _lookup(code, FLOE_SIZES, UNSUPPORTED_FLOES, "floe size")


def code_by_name(name: str, table: dict[int, CodeRange], what: str) -> int:
    """The code of a name in a table (``thin_first_year`` -> 87); ValueError listing names."""
    for code in table.values():
        if code.name == name:
            return code.code
    raise ValueError(f"{name!r} is not a {what}; one of: {', '.join(c.name for c in table.values())}")


def _lookup(code: int, table: dict[int, CodeRange], unsupported: dict[int, str], what: str) -> CodeRange:
    if code in table:
        return table[code]
    if code in unsupported:
        raise ValueError(f"{what} {code:02d} cannot be laid out: {unsupported[code]}")
    allowed = ", ".join(f"{c:02d} {r.name}" for c, r in table.items())
    raise ValueError(f"{code:02d} is not a SIGRID-3 {what} code; one of: {allowed}")
