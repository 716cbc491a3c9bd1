"""Wide floes' cells held out of the contact space going in (``FloeRims``, a part of
``ContactSpace``): only a wide floe's rim is in the engine (``sim_core.ice.wide_floes``,
``inner``); a cell held inside goes in when something may touch it.

- A cell leaving the floe (broken free, or taken out) bares its mates, the floe's cells
  that it may have touched (``expose_mates``).
- Not done: a piece that the hull pushed under surfaces where the hull left it, and a woken
  floe may have been shoved over it meanwhile. It then comes up inside the floe, among
  held cells, and lies there until the cells around it break. Letting the cells it comes
  up under into the engine (to part them, as the engine did when every cell was in it)
  cost the main job its real time in medium floes, in one run: ticks of 60-100 ms for two
  minutes. Keeping such a piece under the floe, tested against the held cells at each
  step, cost it more, in one run: 20-80 ms from the fifth minute on.

The attributes of ``ContactSpace`` are used as they are there (``_tiles``, ``_cp``,
``model``, ``tiles``).
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
        if not len(rows):  # level ice: no work on the step's path
            return
        g = state.gcell[rows]
        count = w.mates_start[g + 1] - w.mates_start[g]
        mates = w.mates[gather_ranges(w.mates_start[g], w.mates_start[g + 1])]
        near = np.repeat(rows - g, count) + mates  # a mate's row: its tile's rows are its template's cells
        self._expose(state, np.unique(near))

    def _expose(self, state: FloeState, rows: np.ndarray) -> None:
        """Put the held shapes of rows (ascending; intact, or bonded to a woken floe) into
        the space, on their floe's body."""
        rows = rows[state.bonded[rows] | (state.status[rows] == FloeStatus.INTACT)]
        for tile in np.unique(state.tile[rows]).tolist():
            mine = rows[state.tile[rows] == tile]
            self._tiles[tile].expose(self._cp, mine - int(self.tiles.row_start[tile]), state.bonded[mine])
