"""The propellers' wash dragging the floes in it (``[ice_dynamics] propeller_wash``): the
floes above water move towards the local water velocity the ship's jets give
(``sim_core.ship.propeller_jet``), by the drag the contact space gives them towards the
uniform water's. Split from ``sim_core.ice.step``."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from sim_core.ice.tiles import IceData

WASH_SHARES = 6  # the wash drags a sixth of the floes in it each step, each by six steps' drag


def drag_in_wash(data: IceData, moving: np.ndarray, wash: Callable[[np.ndarray], np.ndarray], dt: float) -> None:
    """Drag the moving floes above water towards the local water velocity ``wash`` (xy (n, 2)
    m -> velocity (n, 2) m/s, on top of the uniform water's) by the same linear drag as the
    space gives them towards the uniform one (``ContactSpace.set_water_velocity``). Setting
    a body's velocity is a call per floe, so each step takes one of ``WASH_SHARES`` shares of
    the floes in turn and gives it the drag of that many steps: with a drag time of seconds,
    the same as every floe every step, at a sixth of the calls."""
    st, space = data.state, data.contacts
    rows = moving[~st.submerged[moving]]
    data.wash_turn = (data.wash_turn + 1) % WASH_SHARES
    rows = rows[rows % WASH_SHARES == data.wash_turn]
    extra = wash(st.xy[rows])
    hit = np.any(extra != 0.0, axis=1)
    if hit.any():
        rows = rows[hit]
        share = 1.0 - space.space.damping ** (WASH_SHARES * dt)
        space.set_velocity(st, rows, st.vel[rows] + share * extra[hit], st.yaw_rate[rows])
