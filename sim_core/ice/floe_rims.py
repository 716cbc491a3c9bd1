"""Wide floes' cells held out of the contact space going in (``FloeRims``, a part of
``ContactSpace``): only a wide floe's rim is in the engine (``sim_core.ice.wide_floes``,
``inner``); a cell held inside goes in when something may touch it.

- A cell leaving the floe (broken free, or taken out) bares its mates, the floe's cells
  that it may have touched (``expose_mates``).
- A floe surfacing after the hull pushed it under may come up over a floe's inside, where
  the floe was shoved over it: the cells it lies over go in (``expose_under``), so that the
  engine parts them, as it did when every cell was in it. (A floe pushed under a wide floe
  stays under it in nature; here, as for level ice, it surfaces where the hull left it.)

The attributes of ``ContactSpace`` are used as they are there (``_tiles``, ``_cp``,
``model``, ``tiles``, ``extent``).
"""
from __future__ import annotations

import numpy as np

from sim_core.csr import gather_ranges
from sim_core.ice.floes import FloeState, FloeStatus


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

    def expose_under(self, state: FloeState, rows: np.ndarray) -> None:
        """Free rows surfacing bare the held cells whose enclosing circles meet theirs."""
        held = [self.tiles.row_start[t] + np.flatnonzero(b.held) for t, b in self._tiles.items() if b.held.any()]
        if not len(rows) or not held:
            return
        held, at = np.concatenate(held), state.xy[rows]
        reach = 2.0 * float(self.extent.max())
        xy = state.xy[held]
        held = held[np.all((xy > at.min(axis=0) - reach) & (xy < at.max(axis=0) + reach), axis=1)]
        gap = np.hypot(*(state.xy[held][:, None, :] - state.xy[rows][None, :, :]).transpose(2, 0, 1))
        reach = self.extent[state.gcell[held]][:, None] + self.extent[state.gcell[rows]][None, :]
        self._expose(state, held[(gap < reach).any(axis=1)])

    def _expose(self, state: FloeState, rows: np.ndarray) -> None:
        """Put the held shapes of rows (ascending; intact, or bonded to a woken floe) into
        the space, on their floe's body."""
        rows = rows[state.bonded[rows] | (state.status[rows] == FloeStatus.INTACT)]
        for tile in np.unique(state.tile[rows]).tolist():
            mine = rows[state.tile[rows] == tile]
            self._tiles[tile].expose(self._cp, mine - int(self.tiles.row_start[tile]), state.bonded[mine])
