"""Wide floes' cells held out of the contact space going in (``FloeRims``, a part of
``ContactSpace``): only a wide floe's rim is in the engine (``sim_core.ice.wide_floes``,
``inner``); a cell held inside goes in when something may touch it.

- A cell leaving the floe (broken free, or taken out) bares its mates, the floe's cells
  that it may have touched (``expose_mates``).
- A piece that the hull pushed under may lie under a floe's inside when the hull leaves
  it, the floe shoved over it meanwhile: it stays under the floe (``under_held``), as a
  piece rafted under a floe does, until the floe has moved off it. (Surfacing inside the
  floe, with the cells it lies under let into the engine to part them, cost the main job
  its real time in medium floes: ticks of 60-100 ms for two minutes of one run.)

The attributes of ``ContactSpace`` are used as they are there (``_tiles``, ``_cp``,
``model``, ``tiles``, ``extent``, ``_sides``).
"""
from __future__ import annotations

import numpy as np

from sim_core.csr import gather_ranges
from sim_core.ice.floes import FloeState, FloeStatus

FLOE_SHOVE = 100.0  # m: how far a woken floe may have moved from its tile, for ``under_held``'s look


class FloeRims:
    """Held cells going into the space, for ``ContactSpace``."""

    def expose_mates(self, state: FloeState, rows: np.ndarray) -> None:
        """Rows gone from their wide floes bare the cells of the floe that they may have
        touched: those held out of the space go in (``WideFloes.mates``)."""
        w = self.model.wide
        rows = rows[w.of_cell[state.gcell[rows]] >= 0]
        g = state.gcell[rows]
        count = w.mates_start[g + 1] - w.mates_start[g]
        mates = w.mates[gather_ranges(w.mates_start[g], w.mates_start[g + 1])]
        near = np.repeat(rows - g, count) + mates  # a mate's row: its tile's rows are its template's cells
        self._expose(state, np.unique(near))

    def under_held(self, state: FloeState, rows: np.ndarray) -> np.ndarray:
        """Which free rows (n,) bool lie under a wide floe's held cells (their enclosing
        circles meet), so that they stay under the floe rather than surface inside it."""
        reach = 2.0 * float(self.extent.max(initial=0.0)) + FLOE_SHOVE
        at, out = state.xy[rows], np.zeros(len(rows), bool)
        for t, bodies in self._tiles.items():
            lo = self.tiles.corner[t] - reach
            hi = self.tiles.corner[t] + self._sides[self.tiles.template[t]] + reach
            if not bodies.held.any() or not np.any(np.all((at > lo) & (at < hi), axis=1)):
                continue
            held = self.tiles.row_start[t] + np.flatnonzero(bodies.held)
            gap = np.hypot(*(state.xy[held][:, None, :] - at[None, :, :]).transpose(2, 0, 1))
            out |= (gap < self.extent[state.gcell[held]][:, None] + self.extent[state.gcell[rows]][None, :]).any(axis=0)
        return out

    def _expose(self, state: FloeState, rows: np.ndarray) -> None:
        """Put the held shapes of rows (ascending; intact, or bonded to a woken floe) into
        the space, on their floe's body."""
        rows = rows[state.bonded[rows] | (state.status[rows] == FloeStatus.INTACT)]
        for tile in np.unique(state.tile[rows]).tolist():
            mine = rows[state.tile[rows] == tile]
            self._tiles[tile].expose(self._cp, mine - int(self.tiles.row_start[tile]), state.bonded[mine])
