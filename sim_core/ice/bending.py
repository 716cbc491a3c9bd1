"""Bending cracks: the cracks that run out into the level ice where the hull loads its
edge, before the pieces they bound separate.

A floating ice sheet loaded at its edge by a sloping bow fails in bending (Kerr 1976, "The
bearing capacity of floating ice plates subjected to static or quasi-static loads", J.
Glaciology 17(76)): radial cracks run out from the load first and split the edge into
wedges, then a circumferential crack across the wedges at the breaking length frees their
tips as pieces. The numbers are the paper's (Zhang et al. 2023, Table 3, after Lubbad &
Løset 2011): 3, 4 or 5 wedges of 60, 45 or 36 degrees, and a breaking length of 3.3 m at
0.5 m thickness and 4.5 m at 1.0 m, through which ``breaking_length`` fits a power law.
The radial cracks run on, beyond the pieces, as far as the edge load bends the sheet
down: for a semi-infinite beam on an elastic foundation under an end load the deflection
is w ~ exp(-x / (sqrt 2 l_c)) cos(x / (sqrt 2 l_c)) (Hetényi 1946, "Beams on Elastic
Foundation", with l_c the characteristic length of the floating plate), which changes sign
at x = pi l_c / sqrt 2 (``RADIAL_REACH`` l_c, about 2.2 l_c); beyond it the sheet is lifted,
not bent down.

The ice is pre-fractured (the paper's Voronoi cells), so a crack runs along cell edges. A
cracked cell stays intact (held in the sheet) until the hull or a floe breaks it free; its
``FloeState.crack`` label says which crack pattern it lies in, and a crack is drawn on
every edge between cells of different labels where a piece lies on either side or both
cells are cracked (``crack_lines``). Labels: ``PIECE`` set for the cells within the
breaking length, wedge by wedge (their outer edges are the circumferential crack, the
edges between wedges the radial cracks near the load); without it, the cells along a
radial crack beyond the pieces, by the side of the crack they lie on.
"""
from __future__ import annotations

import math

import numpy as np

from sim_core.ice.floes import FloeState, FloeStatus, TilePlacement
from sim_core.ice.model import IceModel
from sim_core.material import characteristic_length

PIECE = 0x80  # label bit: a piece within the breaking length (its wedge in the low bits)
LABELS = 127  # labels 1..127 in the low bits; 0: not cracked
CRACK_EVENT = np.dtype([("row", "<i4"), ("label", "u1")])  # a row cracked, as published
WEDGES = (3, 4, 5)  # wedges a load splits the edge into (paper Table 3)
_TABLE3 = ((0.5, 3.3), (1.0, 4.5))  # (thickness m, breaking length m), paper Table 3
_EXPONENT = math.log(_TABLE3[1][1] / _TABLE3[0][1]) / math.log(_TABLE3[1][0] / _TABLE3[0][0])
RADIAL_REACH = math.pi / math.sqrt(2.0)  # radial cracks' reach in characteristic lengths (Hetényi)
_NO_ROWS = np.zeros(0, dtype=np.int64)
_CRACK_BAND = 0.6  # a radial crack takes the cells within this share of their size from its line


def breaking_length(h: float | np.ndarray) -> np.ndarray:
    """Distance (m) from the load to the circumferential crack in level ice of thickness
    h (m): the power law through the paper's Table 3 (3.3 m at 0.5 m, 4.5 m at 1.0 m),
    L_b = 4.5 m (h / 1 m)^0.447."""
    return _TABLE3[1][1] * (np.asarray(h, dtype=float) / _TABLE3[1][0]) ** _EXPONENT


def outward(point: np.ndarray, hull_xy: np.ndarray, angle: float, stern: float, stem: float,
            half_beam: float) -> np.ndarray:
    """Unit direction (2,) from the hull into the ice at a world point (m): away from the
    nearest point of the hull's centre line, ended half a beam short of stem and stern so
    that directions fan out around the ends."""
    axis = np.array([math.cos(angle), math.sin(angle)])
    along = float(np.clip((point - hull_xy) @ axis, stern + half_beam, stem - half_beam))
    d = point - (hull_xy + along * axis)
    n = float(np.hypot(*d))
    return axis if n < 1e-9 else d / n


def _pattern(seed: int) -> tuple[int, float, int]:
    """A load's wedge count, the turn of its pattern (rad, within a quarter wedge) and
    its label base, from a row number (deterministic: a replay cracks alike)."""
    mixed = (seed * 2654435761) & 0xFFFFFFFF
    wedges = WEDGES[(mixed >> 8) % len(WEDGES)]
    turn = ((mixed >> 16) % 1000 / 1000.0 - 0.5) * 0.5 * math.pi / wedges
    return wedges, turn, mixed % LABELS


def _live_boxes(tiles: TilePlacement, sides: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The live placements and their boxes' lower and upper corners (k, 2), m; ``sides`` (m)
    by template."""
    live = np.flatnonzero(tiles.row_count > 0)
    lo = tiles.corner[live]
    return live, lo, lo + sides[tiles.template[live]][:, None]


def _box_gap(lo: np.ndarray, hi: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Distance (m) from a point to each box (k, 2 corners); 0 inside."""
    gap = np.maximum(np.maximum(lo - point, point - hi), 0.0)
    return np.hypot(gap[:, 0], gap[:, 1])


class _Candidates:
    """The intact rows that any of a step's loads may crack, gathered once for all of them:
    those of the live tiles within the loads' reach, with their places, sizes and tiles'
    boxes. A load then looks only at those near it, where the rows of every live tile near
    it, gathered for each load, took tens of milliseconds in a step whose bow loaded fresh
    ice at many cells (a turn): a tick over two periods."""

    def __init__(self, model: IceModel, st: FloeState, tiles: TilePlacement, points: np.ndarray, reach: float) -> None:
        live, lo, hi = _live_boxes(tiles, np.array([t.side for t in model.templates]))
        near = live[np.any([_box_gap(lo, hi, p) <= reach for p in points], axis=0)] if len(live) else live
        rows = np.concatenate([_NO_ROWS, *(tiles.rows(k) for k in near.tolist())])
        self.rows = rows[st.status[rows] == FloeStatus.INTACT]
        self.home = st.home[self.rows].astype(float)
        self.size = np.sqrt(model.plan_area[st.gcell[self.rows]])
        self._band = _CRACK_BAND * (float(self.size.max()) if len(self.size) else 0.0)  # the widest crack band, m
        self._tile_near = np.zeros(len(tiles.row_count), dtype=bool)  # by placement, refilled per load
        self._tile = st.tile[self.rows]
        self._live, self._lo, self._hi = live, lo, hi

    def near(self, st: FloeState, point: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """The uncracked candidates of the live tiles whose box is within ``reach`` of the
        point (as the load's pattern takes them), less those too far for any label (beyond
        reach plus the widest crack band): (rows, index into the candidates)."""
        self._tile_near[:] = False
        self._tile_near[self._live[_box_gap(self._lo, self._hi, point) <= reach]] = True
        d = self.home - point
        at = np.flatnonzero(self._tile_near[self._tile] & (st.crack[self.rows] == 0)
                            & (d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] <= (reach + self._band) ** 2))
        return self.rows[at], at


def crack_labels(offset: np.ndarray, size: np.ndarray, wedges: int, turn: float, base: int, lb: float,
                 reach: float) -> np.ndarray:
    """Crack label of each cell about one load: its pieces and radial cracks.

    Parameters
    ----------
    offset : (n, 2) the cells' centroids from the load, in the load's frame: x into the
        ice (away from the hull), y across, m.
    size : (n,) the cells' sizes (square root of their plan areas), m.
    wedges : wedges the edge splits into; turn : rad, the pattern's turn about the load.
    base : the load's label base (0..126); lb : the breaking length, reach : the radial
        cracks' reach, m.

    Returns
    -------
    (n,) uint8 labels, 0 where the cell is not cracked by this load.
    """
    out = np.zeros(len(offset), dtype=np.uint8)
    dist = np.hypot(offset[:, 0], offset[:, 1])
    phi = np.arctan2(offset[:, 1], offset[:, 0]) - turn  # (-pi, pi], 0 straight into the ice
    span = math.pi / wedges
    ahead = np.abs(phi) < 0.5 * math.pi
    wedge = np.clip(((phi + 0.5 * math.pi) // span).astype(np.int64), 0, wedges - 1)
    piece = ahead & (dist <= lb)
    out[piece] = PIECE | (1 + (5 * base + wedge[piece]) % LABELS)
    for k in range(1, wedges):
        a = turn - 0.5 * math.pi + k * span
        u = np.array([math.cos(a), math.sin(a)])
        along, across = offset @ u, offset @ np.array([-u[1], u[0]])
        on = ~piece & (along > lb) & (along <= reach) & (np.abs(across) < _CRACK_BAND * size)
        out[on] = 1 + (7 * base + 2 * k + (across[on] > 0)) % LABELS
    return out


def crack_ahead(model: IceModel, st: FloeState, tiles: TilePlacement, loaded: np.ndarray, hull_xy: np.ndarray,
                angle: float, outline: np.ndarray) -> np.ndarray:
    """Crack the level ice about each cell the hull broke (``loaded``, rows) that no earlier
    pattern had cracked (the hull loading fresh ice): label the intact, uncracked cells of
    the live tiles in each such load's pattern (``crack_labels``). A cell that was cracked
    fails along its cracks and starts none: so patterns follow one another about a breaking
    length apart as the bow advances.
    ``outline`` (P, 2) is the hull's waterline in its own frame (x forward, m), ``angle``
    its heading (rad CCW from east). Returns the rows cracked now (ascending)."""
    fresh = loaded[st.crack[loaded] == 0]
    if not len(fresh):
        return _NO_ROWS
    stern, stem = float(outline[:, 0].min()), float(outline[:, 0].max())
    half_beam = float(np.abs(outline[:, 1]).max())
    mat, cracked = model.material, []
    h_max = float(model.thickness[st.gcell[fresh]].max())
    candidates = _Candidates(model, st, tiles, st.home[fresh].astype(float),
                             RADIAL_REACH * characteristic_length(h_max, mat))
    for r in fresh.tolist():
        if st.crack[r] != 0:  # a piece or crack of an earlier load's pattern (this step's) failing
            continue
        h = float(model.thickness[st.gcell[r]])
        reach = RADIAL_REACH * characteristic_length(h, mat)
        point = st.home[r].astype(float)
        rows, at = candidates.near(st, point, reach)
        if not len(rows):
            continue
        n = outward(point, hull_xy, angle, stern, stem, half_beam)
        d = candidates.home[at] - point
        offset = np.column_stack([d @ n, d @ np.array([-n[1], n[0]])])
        wedges, turn, base = _pattern(r)
        labels = crack_labels(offset, candidates.size[at], wedges, turn, base, float(breaking_length(h)), reach)
        hit = labels != 0
        st.crack[rows[hit]] = labels[hit]
        cracked.append(rows[hit])
    return np.unique(np.concatenate([_NO_ROWS, *cracked]))


def crack_events(crack: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The cracked ones of the rows with their labels (``crack``: the label of every row),
    as published (``CRACK_EVENT``)."""
    rows = rows[crack[rows] != 0]
    out = np.empty(len(rows), dtype=CRACK_EVENT)
    out["row"], out["label"] = rows, crack[rows]
    return out


def crack_lines(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether a crack runs on the edge between cells labelled a and b (arrays of labels):
    they differ, and a piece lies on either side or both are cracked."""
    a, b = np.asarray(a, dtype=np.uint8), np.asarray(b, dtype=np.uint8)
    return (a != b) & (((a != 0) & (b != 0)) | (((a | b) & PIECE) != 0))
