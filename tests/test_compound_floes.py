"""A floe wider than the beam moves as a whole until it breaks (issue 26, item 2:
``sim_core.ice.compound_floes``). Its intact cells are one body once a hull comes near: a
slow push moves the floe rigidly, a ram breaks a channel through it while shoving it, and
the cells broken off become floes of their own."""
import dataclasses
import math

import numpy as np
import pytest
import shapely
from conftest import region_world
from pymunk._chipmunk import lib
from test_floe_fields_world import MEDIUM

from sim_core.frames.hull_contour import waterline_contour
from sim_core.ice.chipmunk_bodies import body_at
from sim_core.ice.floe_parts import body_parts
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.model import placed_outlines
from sim_core.ice.step import HullMotion, ice_step
from sim_core.ice.tiles import freeze_tile, new_ice_data, place_tile, reclaim_rows, thaw_tile

DT = 1 / 30
SECONDS = 40.0
STEM = 75.0  # m: the hull's reference point to its stem


@pytest.fixture(scope="module")
def medium(tmp_path_factory):
    """The ice model of 8/10 medium floes, its wide floes moving, and its largest wide floe:
    (template, floe)."""
    model, _ = region_world(tmp_path_factory.getbasetemp() / "pack", 400.0, 600.0, [MEDIUM], -80.0)
    moving = model.ice.settings.model_copy(update={"wide_floes_move": True})
    ice = dataclasses.replace(model.ice, settings=moving)
    w = ice.wide
    floes = [f for t in np.flatnonzero(ice.floe_field) for f in range(w.template_floes[t], w.template_floes[t + 1])]
    floe = max(floes, key=lambda f: w.cells_start[f + 1] - w.cells_start[f])
    template = int(np.searchsorted(w.template_floes, floe, side="right") - 1)
    return ice, template, floe


def _push(medium, speed, seconds=SECONDS):
    """A hull driven north at speed (m/s) into the floe's south edge for seconds: the ice
    data, the floe's rows, where the hull went (its reference point, m), and which rows of
    the ice (n,) the hull ever held under."""
    ice, template, floe = medium
    w = ice.wide
    data = new_ice_data(ice, waterline_contour(150.0, 24.0), 0.1)
    placement = place_tile(ice, data, template, (0.0, 0.0))
    data.contacts.switch_in_now()
    rows = data.tiles.rows(placement)[w.cells[w.cells_start[floe]:w.cells_start[floe + 1]]]
    home = data.state.home[rows]
    x = float(np.median(home[:, 0]))
    y = float(home[np.abs(home[:, 0] - x) < 5.0, 1].min()) - 6.0 - STEM
    hull, went_under = _drive(ice, data, np.array([x, y]), speed, seconds)
    return data, rows, hull, went_under


def _drive(ice, data, hull, speed, seconds):
    """Drive the hull from its reference point (m) north at speed (m/s) for seconds: where it
    went, and which rows of the ice (n,) it held under."""
    x, y = hull
    went_under = np.zeros(data.state.n, bool)
    for _ in range(round(seconds / DT)):
        ice_step(ice, data, (HullMotion(np.array([x, y]), 0.5 * math.pi, np.array([0.0, speed]), 0.0),), DT)
        y += speed * DT
        went_under |= data.state.submerged[:data.state.n]
    return np.array([x, y]), went_under


@pytest.fixture(scope="module")
def pushed(medium):
    return _push(medium, 0.3)


@pytest.fixture(scope="module")
def rammed(medium):
    return _push(medium, 3.0)


def _moved(data, rows):
    """The floe's bonded rows and their displacement from where they lay (n, 2), m."""
    st = data.state
    bonded = rows[st.bonded[rows] & (st.status[rows] == FloeStatus.FREE)]
    return bonded, st.xy[bonded] - st.home[bonded]


def test_a_floe_pushed_slowly_moves_as_a_whole(pushed):
    """At 0.3 m/s the hull crushes a few cells of the floe's edge, then pushes the floe
    ahead of it: every cell moves with the one body, none apart from the others."""
    data, rows, _, _ = pushed
    st = data.state
    bonded, moved = _moved(data, rows)
    assert len(rows) > 300 and len(bonded) > 0.97 * len(rows)
    assert np.mean(moved[:, 1]) > 1.0 and np.all(np.hypot(*moved.T) > 0.3)  # north, all of it
    assert np.mean(st.vel[bonded, 1]) > 0.1  # still going ahead of the hull
    pick = bonded[:: max(1, len(bonded) // 40)]
    apart = lambda p: np.hypot(*(p[:, None, :] - p[None, :, :]).transpose(2, 0, 1))  # noqa: E731
    assert np.abs(apart(st.xy[pick]) - apart(st.home[pick].astype(float))).max() < 0.01  # rigid
    turned = st.yaw[bonded] - st.yaw[bonded[0]]
    assert np.abs(turned).max() < 1e-9  # one body turns as one
    assert np.all(st.cause[bonded] == BreakCause.NONE)


def test_a_floe_rammed_breaks_along_its_cells(rammed, pushed):
    """At 3 m/s the hull breaks a channel into the floe, cell by cell, and shoves what is
    left less than it advanced; the body keeps the mass of the cells still on it."""
    data, rows, hull, _ = rammed
    st = data.state
    bonded, moved = _moved(data, rows)
    broken = rows[~st.bonded[rows]]
    by_hull = np.sum(st.cause[broken] == BreakCause.HULL)  # the others: broken off by floes it pushed
    alone = broken[st.cause[broken] == BreakCause.NONE]  # or left alone by the cells broken around it
    assert by_hull > 100 and len(alone) < 0.02 * len(broken)
    w = data.contacts.model.wide
    for row, g in zip(alone.tolist(), st.gcell[alone].tolist()):  # none of its mates still on the body
        assert not st.bonded[row - g + w.mates[w.mates_start[g]:w.mates_start[g + 1]]].any()
    assert len(bonded) > 0.2 * len(rows)
    assert np.mean(moved[:, 1]) < 0.7 * 3.0 * SECONDS  # shoved, not carried along
    assert by_hull > 10 * np.sum(~pushed[0].state.bonded[pushed[1]])
    c = data.contacts.compounds
    slot = int(st.bond_slot[bonded[0]])
    body = body_at(c.live[slot])
    assert lib.cpBodyGetMass(body) == pytest.approx(data.contacts.model.mass[st.gcell[bonded]].sum(), rel=1e-9)


def _footprints(ice, template: int, cells: np.ndarray) -> np.ndarray:
    """Shapely polygons of a template's cells (template frame, m)."""
    g = ice.templates[template].geometry
    return np.array([shapely.Polygon(g.footprint[g.foot_start[c]:g.foot_start[c + 1]]) for c in cells.tolist()])


def test_only_a_floes_rim_goes_into_the_engine(medium):
    """A wide floe's cells off its outline (``WideFloes.inner``) lie clear of it, and they
    are most of a medium floe's cells: the engine holds and moves its rim only."""
    ice, template, floe = medium
    w = ice.wide
    cells = w.cells[w.cells_start[floe]:w.cells_start[floe + 1]]
    inner = w.inner[ice.template_start[template] + cells]
    outline = shapely.union_all(shapely.buffer(_footprints(ice, template, cells), 1e-3, join_style="mitre")).boundary
    apart = shapely.distance(_footprints(ice, template, cells), outline)
    assert inner.mean() > 0.6 and apart[inner].min() > 0.0 and apart[~inner].max() < 0.01


def test_nothing_touches_a_cell_held_out_of_the_engine(rammed):
    """After the ram, the cells of the floe still held out of the engine (their shapes never
    in the space) are clear of the hull and of every broken cell that the hull never held
    under: the cells that the channel bared went in as it broke them free. (A piece held
    under may surface inside the floe, shoved over it meanwhile: ``floe_rims``, not done.)"""
    data, rows, hull, went_under = rammed
    st, ice = data.state, data.contacts.model
    bodies = data.contacts._tiles[int(st.tile[rows[0]])]
    held = rows[bodies.held[rows - data.tiles.row_start[0]] != 0]
    bonded, _ = _moved(data, rows)
    assert 0 < len(held) and len(held) > 0.3 * len(bonded)

    def placed(r):
        pts, counts = placed_outlines(ice, st.gcell[r], st.xy[r], st.yaw[r])
        return shapely.polygons(shapely.linearrings(pts, indices=np.repeat(np.arange(len(r)), counts)))
    every = np.arange(st.n)
    loose = every[(st.status[every] == FloeStatus.FREE) & ~st.bonded[every] & ~went_under]
    contour = waterline_contour(150.0, 24.0)  # x forward, y starboard; heading north
    at = hull - np.array([0.0, 3.0 * DT])  # where the last step had it
    hull_shape = shapely.Polygon(np.column_stack([at[0] + contour[:, 1], at[1] + contour[:, 0]]))
    assert len(loose) > 5  # pieces broken off the floe that stayed afloat beside it
    assert not shapely.intersects(placed(held), shapely.union_all([*placed(loose), hull_shape])).any()


def test_contacts_on_a_floe_name_its_cells_where_they_are(medium, monkeypatch):
    """The hull's contacts on the floe's body, as each ice step reads them, name the floe's
    cells that hold the contact points, where the body has carried them (a cell the contact
    breaks off leaves the space in that step, and its contact with it)."""
    ice = medium[0]
    data, rows, hull, _ = _push(medium, 0.3, 0.0)
    st, space = data.state, data.contacts
    named = []
    read = space.read_contacts

    def check(state):
        contacts = read(state)
        struck, _, points = contacts.with_hull(0)
        mine = np.isin(struck, rows)
        assert np.all(st.bonded[struck[mine]])
        pts, counts = placed_outlines(ice, st.gcell[struck[mine]], st.xy[struck[mine]], st.yaw[struck[mine]])
        named.extend(shapely.Polygon(ring).distance(shapely.Point(point))
                     for ring, point in zip(np.split(pts, np.cumsum(counts)[:-1]), points[mine]))
        return contacts
    monkeypatch.setattr(space, "read_contacts", check)
    for _ in range(round(SECONDS / DT)):
        hull = hull + np.array([0.0, 0.3 * DT])
        ice_step(ice, data, (HullMotion(hull, 0.5 * math.pi, np.array([0.0, 0.3]), 0.0),), DT)
    assert len(named) >= 5 and max(named) < 0.1  # m: on the cell, where the body carried it


def test_a_frozen_tile_keeps_the_floe_where_it_was_pushed(medium):
    """A tile frozen with a floe moved keeps its cells where they were (as frozen floes: the
    body goes with the tile's engine objects) and thaws them there, one body again, at
    rest; the hull pushing on moves it as a whole again, every cell with it."""
    ice = medium[0]
    unfrozen, rows, hull, _ = _push(medium, 0.3, 20.0)
    data, _, _, _ = _push(medium, 0.3, 20.0)
    again = _freeze_and_thaw(ice, data, _moved(data, rows)[0])
    st = data.state
    before, before_unfrozen = st.xy[again].copy(), unfrozen.state.xy[rows].copy()
    _drive(ice, data, hull, 0.3, 10.0)
    _drive(ice, unfrozen, hull, 0.3, 10.0)
    on = st.bonded[again]  # a cell or two the hull breaks off, as it does with no thaw
    kept, before = again[on], before[on]
    assert len(kept) > 0.98 * len(again) and len(np.unique(st.bond_slot[kept])) == 1
    moved = np.hypot(*(st.xy[kept] - before).T)
    as_if_unfrozen = np.hypot(*(unfrozen.state.xy[rows] - before_unfrozen).T).mean()
    assert moved.min() > 0.5 * as_if_unfrozen > 0.1  # m: pushed on, every cell, about as far as with no thaw
    spread = np.hypot(*(st.xy[kept] - st.xy[kept[0]]).T) - np.hypot(*(before - before[0]).T)
    assert np.abs(spread).max() < 1e-6  # rigidly: each cell as far from the first as before


def _freeze_and_thaw(ice, data, bonded, leaving=None):
    """Freeze tile 0, its objects all out of the space (then call ``leaving``, if given),
    thaw it, and check that the rows that were bonded (n,) are bonded again where they lay,
    on as many bodies as before, each holding the same cells, of its cells' mass, posed so
    that its cells lie where their rows say, and moving as it did. Returns the rows."""
    st, c = data.state, data.contacts.compounds
    cells, where, yaw = bonded - data.tiles.row_start[0], st.xy[bonded].copy(), st.yaw[bonded].copy()
    slots, bodies = np.unique(st.bond_slot[bonded], return_inverse=True)
    velocity = c.velocity[slots].copy()
    freeze_tile(data, 0)
    while data.contacts.swaps_pending:
        data.contacts.step(DT)
    if leaving is not None:
        leaving()
    reclaim_rows(data)
    thaw_tile(ice, data, 0)
    data.contacts.switch_in_now()
    again = data.tiles.row_start[0] + cells
    assert np.array_equal(st.xy[again], where) and np.array_equal(st.yaw[again], yaw)
    assert np.all(st.status[again] == FloeStatus.FREE) and st.bonded[again].all()
    slots, bodies_again = np.unique(st.bond_slot[again], return_inverse=True)
    assert np.array_equal(bodies_again, bodies)
    for k, v in zip(slots.tolist(), velocity):
        mine = again[st.bond_slot[again] == k]
        body = body_at(int(c.body[k]))
        assert k in c.live and lib.cpBodyGetType(body) == lib.CP_BODY_TYPE_DYNAMIC
        assert lib.cpBodyGetMass(body) == pytest.approx(ice.mass[st.gcell[mine]].sum(), rel=1e-9)
        at_cog = lib.cpBodyGetVelocity(body)
        assert np.allclose([at_cog.x, at_cog.y, lib.cpBodyGetAngularVelocity(body)], v, rtol=0.0, atol=1e-5)
        at, angle = lib.cpBodyGetPosition(body), lib.cpBodyGetAngle(body)
        turn = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])
        assert np.allclose(st.bond_xy[mine] @ turn.T + [at.x, at.y], st.xy[mine], rtol=0.0, atol=1e-6)
    return again


def _rested(medium):
    """A floe pushed for 20 s, then left while the hull lies 2 km away until the floe's body
    rests: the ice data, the floe's rows, where the hull pushed from, the body's slot and
    the hull lying away."""
    ice = medium[0]
    data, rows, hull, _ = _push(medium, 0.3, 20.0)
    c, st = data.contacts.compounds, data.state
    slot = int(st.bond_slot[_moved(data, rows)[0][0]])
    away = HullMotion(hull - np.array([0.0, 2000.0]), 0.5 * math.pi, np.zeros(2), 0.0)
    for _ in range(round(60.0 / DT)):
        ice_step(ice, data, (away,), DT)
        if slot in c.resting:
            break
    assert slot in c.resting
    return data, rows, hull, slot, away


def test_a_floe_far_from_the_hull_rests_and_wakes_again(medium):
    """A floe pushed and left rests as a static body far from the hull (no solver work, no
    drift in the field's frame); the hull coming back wakes it."""
    ice = medium[0]
    data, rows, hull, slot, away = _rested(medium)
    c, st = data.contacts.compounds, data.state
    bonded, _ = _moved(data, rows)
    where = st.xy[bonded].copy()
    for _ in range(30):
        ice_step(ice, data, (away,), DT)
    assert np.array_equal(st.xy[bonded], where)
    ice_step(ice, data, (HullMotion(hull, 0.5 * math.pi, np.zeros(2), 0.0),), DT)
    assert slot not in c.resting and slot in c.live


def test_a_floe_resting_when_its_tile_freezes_stays_out_of_the_way(medium):
    """A floe at rest when its tile freezes leaves with the tile: a hull coming back to
    where it lay, before and after the tile thaws, wakes nothing of it (its resting body
    was once left among the resting and woken from there, with no body to wake)."""
    ice = medium[0]
    data, _, hull, slot, _ = _rested(medium)
    c = data.contacts.compounds
    freeze_tile(data, 0)
    back = HullMotion(hull, 0.5 * math.pi, np.zeros(2), 0.0)
    while data.contacts.swaps_pending:
        ice_step(ice, data, (back,), DT)
    reclaim_rows(data)
    thaw_tile(ice, data, 0)
    data.contacts.switch_in_now()
    for _ in range(3):
        ice_step(ice, data, (back,), DT)
    assert slot not in c.live and slot not in c.resting


@pytest.fixture(scope="module")
def rammed_through(medium):
    return _push(medium, 5.0)


def test_a_floe_the_hull_cuts_in_two_parts_into_two_bodies(medium, rammed_through):
    """At 5 m/s the hull breaks a channel right through the floe (``floe_parts``): the cells
    left on either side are each a body of their own, with their own cells' mass, each
    body's cells hang together, and the two parts go their own ways, pushed aside by the
    hull passing between them; a cell the channel left alone is a floe of its own."""
    ice = medium[0]
    data, rows, hull, _ = rammed_through
    st, c = data.state, data.contacts.compounds
    bonded, _ = _moved(data, rows)
    slots, count = np.unique(st.bond_slot[bonded], return_counts=True)
    assert len(slots) >= 2 and np.sort(count)[-2] > 0.2 * len(rows)
    west, east = (bonded[st.bond_slot[bonded] == k] for k in slots[np.argsort(count)[-2:]])
    if st.xy[west, 0].mean() > st.xy[east, 0].mean():
        west, east = east, west
    assert st.xy[west, 0].max() < hull[0] < st.xy[east, 0].min()  # one part either side of the hull's track
    assert st.vel[west, 0].mean() < -0.05 and st.vel[east, 0].mean() > 0.05  # shoved apart
    for k in slots.tolist():
        mine = bonded[st.bond_slot[bonded] == k]
        mass = lib.cpBodyGetMass(body_at(int(c.body[k])))
        assert mass == pytest.approx(ice.mass[st.gcell[mine]].sum(), rel=1e-9)
        pts, counts = placed_outlines(ice, st.gcell[mine], st.xy[mine], st.yaw[mine])
        cells = shapely.polygons(shapely.linearrings(pts, indices=np.repeat(np.arange(len(mine)), counts)))
        assert shapely.get_num_geometries(shapely.union_all(shapely.buffer(cells, 0.05))) == 1  # in one piece
    alone = rows[~st.bonded[rows] & (st.status[rows] == FloeStatus.FREE) & (st.cause[rows] == BreakCause.NONE)]
    tile = data.contacts._tiles[0]
    assert np.all(tile.floe_body[alone - data.tiles.row_start[0]] != 0)
    assert len(tile.parts) >= 1

    def gone():  # the parts' bodies leave with the tile's, and the floe thaws where it lay
        assert not any(k in c.live for k in slots.tolist())
    _freeze_and_thaw(ice, data, bonded, gone)


def test_a_bodys_parts_are_its_cells_joined_through_mates():
    """``body_parts`` joins a body's cells through chains of mates on the body: of cells 10,
    11, 12, 14, 15 and 17, 11 and 12 are mates and so are 15 and 17; 10 reaches 11 only
    through 13, and 14 has only 16, neither of them on the body: four parts."""
    pairs = [(11, 12), (10, 13), (13, 11), (15, 17), (14, 16)]
    both = sorted(pairs + [(b, a) for a, b in pairs])
    start = np.searchsorted(np.array([a for a, _ in both]), np.arange(19))
    mates = np.array([b for _, b in both])
    part, parts = body_parts(np.array([10, 11, 12, 14, 15, 17]), start, mates)
    assert parts == 4 and part.tolist() == [0, 1, 1, 2, 3, 3]


def test_reruns_of_a_ram_are_the_same(medium, rammed):
    """The engine lists contacts in an order that differs from run to run; what the floe's
    body gets back from its broken cells does not depend on it, so a rerun (a save point's
    re-simulation) is the same run, to the bit."""
    again, rows, _, _ = _push(medium, 3.0)
    assert np.array_equal(again.state.xy[rows], rammed[0].state.xy[rows])
    assert np.array_equal(again.state.bonded[rows], rammed[0].state.bonded[rows])
