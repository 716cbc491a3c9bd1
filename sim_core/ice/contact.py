"""Planar contact of hulls, intact cells and free floes, on Chipmunk2D (through pymunk).

Chipmunk does the collision detection and the contact impulses; this module keeps its
bodies in step with the floe arrays, through Chipmunk's C API (``chipmunk_bodies`` says why).

All intact cells of a placed tile are shapes of one static body, so the per-step body walk
sees a few tile bodies, not thousands of cells. A contact on a tile body is traced to its
cell by the Voronoi property: the cell holding a point is the one with the nearest seed. A
contact point lies on the loaded cell's boundary, and the neighbour across that boundary is
already broken (that is where the striker came from), so the nearest seed among the tile's
intact cells names the loaded cell; a sphere collider lies inside its cell, so there the
answer is exact. The seeds are searched in a uniform grid of buckets per template, in the
template's frame (``contact_kernels.seed_grid``). Breaking moves a cell's shape from its
tile body to a new dynamic body. Colliders (mesh or sphere) carry the floe-floe contact,
but the hull breaks whatever it touches geometrically: the hull's overlap with intact
cells is tested against their true outlines (separating axes, in numba), not through the
engine. Each hull is a kinematic body driven by its ship's model (``hull_bodies``; one per
ship, all in this one space). State moves between Chipmunk and the arrays through
``pymunk.batch`` (one C call per step, no Python loop over bodies). Water drag in the
plane is Chipmunk's velocity damping, an exponential decay with the configured time
constant, applied in C. A quadratic drag would need a Python callback per body and step.

A tile enters the space in two parts: ``build_tile`` makes its static body and shapes
(the costly part, a few microseconds per cell, done ahead of need) and ``insert_tile``
adds them to the space (about a microsecond per cell), so crossing the detection radius
only switches a prepared tile in.
"""
from __future__ import annotations

import math
import weakref
from collections.abc import Iterator

import numpy as np
import pymunk
import pymunk.batch as pb
from pymunk._chipmunk import ffi, lib

from sim_core.ice.chipmunk_bodies import (
    FLOE_FILTER,
    NO_CONTACT,
    ROW0,
    TileBodies,
    body_at,
    free_all,
    new_shape,
    ptr_of,
    shape_at,
)
from sim_core.ice.compound_floes import CompoundFloes, CompoundSlots, bond_rows, scatter_bonded
from sim_core.ice.compound_rest import CompoundRest
from sim_core.ice.compound_thaw import CompoundThaw
from sim_core.ice.contact_kernels import Contacts, contact_rows, hull_overlaps, scatter_free, seed_grid
from sim_core.ice.contact_resting import FloeRest
from sim_core.ice.contact_swaps import TileSwaps
from sim_core.ice.floe_parts import FloeParts
from sim_core.ice.floe_rims import FloeRims
from sim_core.ice.floes import FloeState, TilePlacement
from sim_core.ice.hull_bodies import HullBody, move_hull, new_hull
from sim_core.ice.model import IceModel, placed_outlines

_ROW_BY_ROW = 16  # fewer rows than this have their engine objects looked up one by one
_BODY_FIELDS = (pb.BodyFields.BODY_ID | pb.BodyFields.POSITION | pb.BodyFields.ANGLE
                | pb.BodyFields.VELOCITY | pb.BodyFields.ANGULAR_VELOCITY)
_ARB_FIELDS = (pb.ArbiterFields.BODY_A_ID | pb.ArbiterFields.BODY_B_ID | pb.ArbiterFields.TOTAL_IMPULSE
               | pb.ArbiterFields.NORMAL | pb.ArbiterFields.CONTACT_COUNT | pb.ArbiterFields.POINT_A_1
               | pb.ArbiterFields.POINT_A_2)  # a contact's points on body a only: its mean point is all we use


class ContactSpace(FloeRest, CompoundFloes, CompoundRest, CompoundThaw, FloeParts, FloeRims, TileSwaps):
    """Chipmunk space holding the hulls and the floes of breakable tiles."""

    def __init__(self, model: IceModel, tiles: TilePlacement, hull_outline: np.ndarray,
                 hull_friction: float) -> None:
        s = model.settings
        self.model, self.tiles = model, tiles
        self.space = pymunk.Space()
        self._cp = self.space._space  # the C space, for the C API calls below
        self.space.iterations = s.solver_iterations
        self.space.collision_slop = s.collision_slop
        # Chipmunk's sleeping stays off. Through the C API it no longer hung (the pymunk-object
        # design once hung in cpSpaceStep after a few thousand mesh-collider steps; three mesh
        # runs and two 1500 m transits with sleeping on ran through here), and it halved the
        # median step of the default transit. But it sleeps and wakes whole touching groups,
        # and the packed channel astern is one group of thousands: one touch, or the removal
        # of one frozen floe, woke them all, in steps of 0.1-1.1 s. Putting single floes to
        # sleep (cpBodySleep) breaks its rule that touching bodies sleep together, and freed
        # its contact memory twice. Floes at rest leave the dynamic set one by one instead, as
        # static bodies (``rest``, ``wake``; sim_core/ice/resting.py decides when).
        self.space.damping = math.exp(-1.0 / s.drag_time_s)  # per second: v *= damping ** dt
        self._water = (0.0, 0.0, 0.0)  # the water's velocity (m/s) and the step (s) the gravity was set for
        self.hulls: list[HullBody] = []  # by index: every ship's hull breaks ice in this one space
        self._tiles: dict[int, TileBodies] = {}  # placement -> its engine objects
        self.compounds = CompoundSlots()  # wide floes' bodies (``compound_floes``)
        self._tile_index: tuple | None = None  # _in_space's arrays, until _tiles or the placements change
        self._entering: list[TileBodies] = []  # switched in, objects still going into the space
        self._leaving: list[tuple[int, TileBodies]] = []  # switched out, objects still to take out
        self._insert_budget, self._removal_work = s.swap_objects_per_step, s.swap_removal_work
        self._rest_work = s.rest_search_work
        self._arbiters = 0  # contacts Chipmunk kept at the last read
        self._moving_at = np.zeros(0, dtype=np.int64)  # the moving floes' places among the bodies, last read
        # floes shedding their contacts before they rest: (the engine's time stamp from which
        # they may, their rows, the rows' placements and bodies, and those placements' engine
        # objects), oldest first (``rest``, ``settle``)
        self._shedding: list[tuple[int, np.ndarray, np.ndarray, np.ndarray, dict[int, TileBodies]]] = []
        d = np.hypot(model.outline[:, 0], model.outline[:, 1])
        self.extent = np.maximum.reduceat(d, model.outline_start[:-1]) if len(d) else np.zeros(0)  # cell radius, m
        self.reach = 0.0  # m: farthest a point of a hull and of a cell it touches can be from its reference point
        self._grid = seed_grid(model)
        # per template, the farthest a cell's outline lies from its Voronoi seed, m
        spread = np.hypot(*model.seed_offset.T) + self.extent if len(self.extent) else np.zeros(0)
        self._pad = np.array([spread[a:b].max(initial=0.0) for a, b in zip(model.template_start[:-1],
                                                                           model.template_start[1:])])
        self._sides = np.array([t.side for t in model.templates], dtype=float)
        self._buffer = pb.Buffer()
        self._hull_objects: list[tuple[int, int]] = []  # each hull's C body and shape, for free_all
        weakref.finalize(self, free_all, self.space, self._tiles, self._leaving, self._hull_objects)
        self.add_hull(hull_outline, hull_friction)

    def add_hull(self, outline: np.ndarray, friction: float) -> int:
        """Add a hull of the given waterline outline ((n, 2) m, body frame: x forward, y to
        port) and friction against ice; returns its index."""
        hull = new_hull(self._cp, len(self.hulls), outline, friction)
        self.hulls.append(hull)
        self._hull_objects.append((hull.body, hull.shape))
        self.reach = max(self.reach, hull.radius + float(self.extent.max(initial=0.0)))
        return len(self.hulls) - 1

    # -- building -------------------------------------------------------------------------
    def build_cells(self, bodies: TileBodies, template: int, home: np.ndarray, yaw: float, cells: np.ndarray) -> None:
        """Make, outside the space, the intact-cell shapes of cells (offsets in the template)
        of a tile of the template that lays them at home (n, 2) m and yaw (rad,
        ``placed_centroids``), on the tile's static body (a wide floe's, on the floe's own);
        ``insert_tile`` switches them in."""
        m = self.model
        g = int(m.template_start[template]) + cells
        rings = self._rings(g, home, np.full(len(cells), yaw))
        friction = m.settings.ice_friction
        for j, gi, floe, centre, ring, sphere in zip(cells.tolist(), g.tolist(), m.wide.of_cell[g].tolist(),
                                                     home.tolist(), rings, m.is_sphere[g].tolist()):
            body = body_at(bodies.body if floe < 0 else bodies.wide_body(floe))
            bodies.intact[j] = new_shape(body, ring, float(m.radius[gi]), tuple(centre), sphere, friction)
        held = cells[bodies.hold[cells]]  # a wide floe's cells off its outline wait outside the space
        bodies.held[held], bodies.intact[held] = bodies.intact[held], 0

    def build_floes(self, bodies: TileBodies, offsets: np.ndarray, gcell: np.ndarray, xy: np.ndarray,
                    yaw: np.ndarray, vel: np.ndarray, yaw_rate: np.ndarray) -> None:
        """Make, outside the space, dynamic bodies for a tile's cells at offsets, of global
        cells gcell (n,), at poses xy (n, 2) m and yaw (n,) rad, with velocities vel (n, 2)
        m/s and yaw_rate (n,) rad/s; ``name_floes`` gives them their rows, ``insert_tile``
        or ``TileBodies.insert`` switch them in."""
        m = self.model
        rings = self._rings(gcell, np.zeros((len(gcell), 2)), np.zeros(len(gcell)))
        friction = m.settings.ice_friction
        for j, gi, ring, sphere, at, angle, v, w in zip(offsets.tolist(), gcell.tolist(), rings,
                                                         m.is_sphere[gcell].tolist(), xy.tolist(), yaw.tolist(),
                                                         vel.tolist(), yaw_rate.tolist()):
            body = lib.cpBodyNew(float(m.mass[gi]), float(m.inertia[gi, 2]))
            lib.cpBodySetPosition(body, (at[0], at[1]))
            lib.cpBodySetAngle(body, angle)
            lib.cpBodySetVelocity(body, (v[0], v[1]))
            lib.cpBodySetAngularVelocity(body, w)
            bodies.floe_body[j] = ptr_of(body)
            bodies.floe_shape[j] = new_shape(body, ring, float(m.radius[gi]), (0.0, 0.0), sphere, friction)

    @staticmethod
    def name_floes(bodies: TileBodies, offsets: np.ndarray, rows: np.ndarray) -> None:
        """Give the floe bodies at offsets their rows (a body names its floe's row)."""
        for j, row in zip(offsets.tolist(), rows.tolist()):
            lib.cpBodySetUserData(body_at(int(bodies.floe_body[j])), ffi.cast("void *", ROW0 + row))

    def _rings(self, g: np.ndarray, at: np.ndarray, angle: np.ndarray) -> list[list]:
        """Outlines of cells g placed at (at, angle), as lists of (x, y) for Chipmunk."""
        pts, counts = placed_outlines(self.model, g, at, angle)
        pts, ends = pts.tolist(), np.cumsum(counts).tolist()
        return [pts[a:b] for a, b in zip([0] + ends[:-1], ends)]

    def free(self, state: FloeState, rows: np.ndarray) -> None:
        """Intact or bonded rows leave their tile's or floe's body, each for a dynamic body of
        its own, now, and so do the cells of a floe's body that their leaving left alone
        (``floe_parts``)."""
        if np.any(state.bonded[rows]):
            rows = np.union1d(rows, self.unbond(state, rows[state.bonded[rows]]))
        for tile in np.unique(state.tile[rows]).tolist():
            bodies, start = self._tiles[tile], int(self.tiles.row_start[tile])
            mine = rows[state.tile[rows] == tile]
            j = mine - start
            bodies.remove(self._cp, j)
            self.build_floes(bodies, j, state.gcell[mine], state.xy[mine], state.yaw[mine], state.vel[mine],
                             state.yaw_rate[mine])
            self.name_floes(bodies, j, mine)
            bodies.insert(self._cp, j)
        self.expose_mates(state, rows)

    def remove(self, state: FloeState, rows: np.ndarray) -> None:
        """Take intact or free rows of tiles in the space out of it, now, and free their
        engine objects."""
        for tile in np.unique(state.tile[rows]).tolist():
            bodies, start = self._tiles[tile], int(self.tiles.row_start[tile])
            bodies.remove(self._cp, rows[state.tile[rows] == tile] - start)
        self.expose_mates(state, rows)

    def discard(self, bodies: TileBodies) -> None:
        """Free a built tile that was never switched in."""
        bodies.release(self._cp)

    def has_tile(self, placement: int) -> bool:
        """Whether the placement's bodies are in the space."""
        return placement in self._tiles

    def _floe_objects(self, state: FloeState, rows: np.ndarray, kind: str) -> np.ndarray:
        """The engine objects (``"floe_body"`` or ``"floe_shape"``; C pointers, uintp) of
        free rows (n,) in the space: row by row for a few (most steps' floes going under,
        surfacing or waking), tile by tile for more (floes going to rest); the two cost the
        same at about 16 rows (2 us for one row, 13 us for 200 tile by tile)."""
        if len(rows) < _ROW_BY_ROW:
            start = self.tiles.row_start
            return np.array([getattr(self._tiles[t], kind)[i - start[t]] for i, t in
                             zip(rows.tolist(), state.tile[rows].tolist())], dtype=np.uintp)
        out = np.empty(len(rows), dtype=np.uintp)
        for bodies, at, offsets in self._by_tile(state, rows):
            out[at] = getattr(bodies, kind)[offsets]
        return out

    def _by_tile(self, state: FloeState, rows: np.ndarray) -> Iterator[tuple[TileBodies, np.ndarray, np.ndarray]]:
        """The free rows (n,) tile by tile: each tile's engine objects, which of the rows
        (a flag each) are its, and their offsets in it."""
        tiles = state.tile[rows]
        local = rows - self.tiles.row_start[tiles]
        for t in np.unique(tiles).tolist():
            at = tiles == t
            yield self._tiles[t], at, local[at]

    def _floe_shapes(self, state: FloeState, rows: np.ndarray) -> list[int]:
        return self._floe_objects(state, rows, "floe_shape").tolist()

    def _floe_bodies(self, state: FloeState, rows: np.ndarray) -> list[int]:
        return self._floe_objects(state, rows, "floe_body").tolist()

    def set_submerged(self, state: FloeState, rows: np.ndarray, submerged: bool) -> None:
        """Take free rows out of (or back into) all planar contact: floes under the hull. A
        floe going under is pinned by the hull and loses its planar velocity, and its shape
        leaves the space until it surfaces (``TileBodies.sink``): in a jam of 583 floes
        under the hull that took the engine step from 6.35 to 5.8 ms (median, 2 cores)."""
        f = NO_CONTACT if submerged else FLOE_FILTER
        for p in self._floe_shapes(state, rows):
            lib.cpShapeSetFilter(shape_at(p), f)
        for bodies, _, offsets in self._by_tile(state, rows):
            (bodies.sink if submerged else bodies.lift)(self._cp, offsets)
        if submerged:
            self.set_velocity(state, rows, np.zeros((len(rows), 2)), np.zeros(len(rows)))

    def set_velocity(self, state: FloeState, rows: np.ndarray, velocity: np.ndarray, yaw_rate: np.ndarray) -> None:
        """Give free rows (their bodies and state) a planar velocity (n, 2) m/s, yaw rate (n,) rad/s."""
        state.vel[rows], state.yaw_rate[rows] = velocity, yaw_rate
        for p, v, w in zip(self._floe_bodies(state, rows), velocity.tolist(), yaw_rate.tolist()):
            lib.cpBodySetVelocity(body_at(p), (v[0], v[1]))
            lib.cpBodySetAngularVelocity(body_at(p), w)

    # -- per step -------------------------------------------------------------------------
    def set_hull(self, hull: int, xy: np.ndarray, angle: float, velocity: np.ndarray,
                 angular_velocity: float) -> None:
        """Pose (world m, rad CCW) and velocity (m/s, rad/s CCW) of a kinematic hull (by
        index) for the coming step."""
        move_hull(self._cp, self.hulls[hull], xy, angle, velocity, angular_velocity)

    def _in_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The placements in the space (k,), their south-west and north-east corners (k, 2;
        m) and a flag per placement (tiles.n,) set for those in the space; made again only
        when the tiles in the space or the placements change."""
        if self._tile_index is None or len(self._tile_index[3]) != self.tiles.n:
            ids = np.fromiter(self._tiles, dtype=np.int64, count=len(self._tiles))
            lo = self.tiles.corner[ids]
            working = np.zeros(self.tiles.n, dtype=np.uint8)
            working[ids] = 1
            self._tile_index = (ids, lo, lo + self._sides[self.tiles.template[ids]][:, None], working)
        return self._tile_index

    def hull_touching(self, state: FloeState, index: int) -> np.ndarray:
        """Rows of intact cells in the space whose true outline the hull (by index)
        overlaps now (kinematic-static pairs make no contacts in Chipmunk, and sphere
        colliders are not the cells' outlines)."""
        m, body = self.model, self.hulls[index]
        xy, angle = body.xy, body.angle
        c, s = math.cos(angle), math.sin(angle)
        hull = body.in_world()
        tiles, lo, hi, _ = self._in_space()
        near = tiles[np.all((lo <= hull.max(axis=0)) & (hi >= hull.min(axis=0)), axis=1)]  # a tile's cells lie in it
        if not len(near):
            return np.zeros(0, dtype=np.int64)
        tl = self.tiles
        found = hull_overlaps(near, np.concatenate([self._tiles[k].in_space for k in near.tolist()]), state.status,
                               state.gcell, state.xy, state.yaw, m.outline, m.outline_start, self.extent, hull, xy,
                               c, s, body.box, tl.template, tl.corner, tl.quarter_turns, tl.row_start,
                               tl.row_count, self._sides, self._pad, *self._grid[:5])
        return np.sort(found)

    def set_water_velocity(self, east: float, north: float, dt: float) -> None:
        """Let the water move at (``east``, ``north``) m/s (world x, y) over the next step
        of dt (s): the floes' planar drag then pulls them towards it rather than to rest.
        Chipmunk's damping decays a body's velocity to zero (v <- v d + g dt, d = damping ** dt);
        a uniform acceleration g = v_w (1 - d) / dt, given as the space's gravity (which
        acts on the moving floes only, not on the kinematic hull or floes at rest), makes
        v_w the steady state: the same linear drag, relative to the water."""
        if (east, north, dt) == self._water:  # most steps: as the last one
            return
        self._water = (east, north, dt)
        share = (1.0 - self.space.damping ** dt) / dt
        self.space.gravity = (east * share, north * share)

    def step(self, dt: float) -> None:
        """Switch the step's share of tile objects in or out, then step the engine by dt (s)."""
        self._swap_work()
        self.engine_step(dt)

    def engine_step(self, dt: float) -> None:
        """The bare engine step of dt (s), ``cpSpaceStep``. Called through the C API: the
        floes are no pymunk objects, so pymunk's ``Space.step`` would only add its
        bookkeeping of them."""
        lib.cpSpaceStep(self._cp, dt)

    def read_free(self, state: FloeState) -> np.ndarray:
        """Copy pose and velocity of the moving free floes (not resting) from Chipmunk into
        the arrays; returns their rows, in the order of the space's dynamic bodies."""
        buf = self._buffer
        buf.clear()
        pb.get_space_bodies(self.space, _BODY_FIELDS, buf)  # the dynamic bodies first, in the space's order
        ids = np.frombuffer(buf.int_buf(), dtype=np.uintp)
        f = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ids), 6)
        moving, self._moving_at = scatter_free(ids, f, state.status, state.resting, state.xy, state.yaw, state.vel,
                                               state.yaw_rate)
        if self.compounds.live:
            c, w = self.compounds, self.model.wide
            scatter_bonded(ids, f, state.status, state.bonded, state.bond_slot, self._in_space()[3],
                           self.tiles.row_start, c.placement, c.floe, c.cog, c.velocity, w.cells_start, w.cells,
                           state.bond_xy, state.bond_yaw, state.xy, state.yaw, state.vel, state.yaw_rate)
        return moving

    def read_contacts(self, state: FloeState) -> Contacts:
        """Contacts of the last step, in Chipmunk's order (which follows hashes of C
        pointers and so differs from run to run: sums over contacts must not depend on it)."""
        buf = self._buffer
        buf.clear()
        pb.get_space_arbiters(self.space, _ARB_FIELDS, buf)
        ints = np.frombuffer(buf.int_buf(), dtype=np.uintp).reshape(-1, 3)
        f = np.frombuffer(buf.float_buf(), dtype=np.float64).reshape(len(ints), 8)
        self._arbiters = len(ints)
        tiles = self.tiles
        working = self._in_space()[3]
        a, b, point = contact_rows(ints, f, state.status, working, tiles.template, tiles.corner,
                                    tiles.quarter_turns, tiles.row_start, self._sides, *self._grid)
        if self.compounds.n:
            c = self.compounds
            c.read_poses()
            bond_rows(ints, point, a, b, state.status, state.bonded, state.bond_slot, working, tiles.template,
                      tiles.corner, tiles.quarter_turns, tiles.row_start, self._sides, c.placement, c.floe, c.pose,
                      self.model.wide.of_cell, *self._grid)
        return Contacts(a, b, f[:, 0:2].copy(), f[:, 2:4].copy(), point)
