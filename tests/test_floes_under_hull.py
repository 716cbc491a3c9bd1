"""Floes under the hull: which go under, and their engine objects while they are there."""
import numpy as np
from pymunk._chipmunk import ffi, lib

from sim_core.fracture.tile_template import FractureSettings, build_tile
from sim_core.frames.hull_contour import waterline_contour
from sim_core.ice.chipmunk_bodies import FLOE_FILTER, body_at, shape_at
from sim_core.ice.floes import BreakCause
from sim_core.ice.model import compile_ice_model
from sim_core.ice.step import HullMotion, _update_submersion
from sim_core.ice.tiles import break_cells, new_ice_data, place_tile

NONE = np.zeros(0, dtype=np.int64)


def one_floe():
    """A 40 m tile of 0.5 m ice with one cell broken free and no other cell in the engine,
    the default ship's hull (150 m x 24 m); returns the model, the data and the floe's row."""
    m = compile_ice_model([build_tile(0.5, 4, FractureSettings(tile_side=40.0, colliders="mesh"))])
    data = new_ice_data(m, waterline_contour(150, 24), 0.1)
    rows = data.tiles.rows(place_tile(m, data, 0, (0.0, 0.0)))
    one = rows[[len(rows) // 2]]
    data.contacts.remove(data.state, np.setdiff1d(rows, one))
    break_cells(data, one, BreakCause.HULL)
    return m, data, int(one[0])


def hull_at(xy) -> HullMotion:
    """The hull at rest heading east, its reference point (midship) at xy (m)."""
    return HullMotion(np.asarray(xy, dtype=float), 0.0, np.zeros(2), 0.0)


def test_a_floe_jammed_beside_the_hull_stays_afloat_and_moving():
    """A floe jammed against an edge goes under the hull only where the hull covers it.
    Beside the hull it stays afloat with its velocity; it used to be sent under and
    surface in the same step, pinned and dropped a thickness every step it stayed jammed."""
    m, data, row = one_floe()
    st = data.state
    data.contacts.set_velocity(st, np.array([row]), np.array([[0.3, 0.1]]), np.array([0.02]))
    heave = float(st.heave[row])
    x, y = st.xy[row]
    jammed = np.array([row])
    _update_submersion(m, data, 0, hull_at((x, y - 30.0)), NONE, jammed)  # 30 m to port of the centre line
    assert not st.submerged[row]
    assert np.allclose(st.vel[row], (0.3, 0.1)) and abs(st.yaw_rate[row] - 0.02) < 1e-6
    assert st.heave[row] == heave
    _update_submersion(m, data, 0, hull_at((x - 100.0, y)), NONE, jammed)  # aft of the stern, outside it
    assert not st.submerged[row]
    _update_submersion(m, data, 0, hull_at((x - 20.0, y)), NONE, jammed)  # under the hull's fore body
    assert st.submerged[row] and np.all(st.vel[row] == 0.0)


def test_a_floe_under_the_hull_leaves_the_engine_until_it_surfaces():
    """Going under takes the floe's shape out of the engine (its body stays); surfacing
    brings it back, colliding again; and a floe under the hull can leave the engine with
    its tile (Chipmunk aborts on removing a shape that is not in the space)."""
    m, data, row = one_floe()
    st, space = data.state, data.contacts
    shape = shape_at(space._floe_shapes(st, np.array([row]))[0])
    body = body_at(space._floe_bodies(st, np.array([row]))[0])
    x, y = st.xy[row]
    struck = np.array([row])

    def in_engine() -> tuple[bool, bool]:
        return lib.cpShapeGetSpace(shape) != ffi.NULL, lib.cpBodyGetSpace(body) != ffi.NULL

    assert in_engine() == (True, True)
    _update_submersion(m, data, 0, hull_at((x - 20.0, y)), struck)
    assert st.submerged[row] and in_engine() == (False, True)
    _update_submersion(m, data, 0, hull_at((x + 100.0, y)), NONE)  # the hull has passed over it
    assert not st.submerged[row] and in_engine() == (True, True)
    f = lib.cpShapeGetFilter(shape)
    assert (f.group, f.categories, f.mask) == FLOE_FILTER
    _update_submersion(m, data, 0, hull_at((x - 20.0, y)), struck)
    assert in_engine() == (False, True)
    space.remove(st, struck)
    space.space.step(0.1)
    assert len(space.read_free(st)) == 0  # its body went with it
