"""The scene's tile switches carried out in the ice world, and what a step publishes of them.

A tile the hull comes near is placed (given floe rows) or thawed; one far astern is frozen
(its rows given up, its broken cells kept as ``FROZEN_FLOE_EVENT`` records). Tiles are
prepared ahead of their switch, within a wall-time budget per step, so that the switch
itself only hands the prepared engine objects over (paper section 2.4, the improved
quadtree's swap). Functions of the world's model and data (``sim_core.world``).
"""
from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba
import numpy as np
import shapely

from sim_core.ice.bending import crack_events
from sim_core.ice.floes import NO_FROZEN_CRACKS, FloeStatus, TilePlacement, frozen_crack_records
from sim_core.ice.model import placed_outlines
from sim_core.ice.tiles import (
    IceData,
    PreparedTile,
    advance,
    discard_prepared,
    freeze_tile,
    place_tile,
    prepare_place,
    prepare_thaw,
    reclaim_rows,
    thaw_tile,
)
from sim_core.scene.quadtree import tiles_near
from sim_core.scene.scene import SceneUpdate, TileState, tile_corner, tile_layout, tiles_to_prepare

if TYPE_CHECKING:
    from sim_core.world import WorldData, WorldModel

NO_ROWS = np.zeros(0, dtype=np.int64)
_PREPARE_CHUNK = 64  # cells built between looks at the clock while preparing tiles ahead
_NO_ROWS = np.zeros(0, dtype=np.int64)
# A frozen tile's broken cell as published: placement, offset in the tile, what broke it
# (BreakCause), and its pose (x, y, heave, yaw, roll, pitch; world m and rad) in float32,
# as floe poses travel on the stream. 33 bytes.
FROZEN_FLOE_EVENT = np.dtype([("placement", np.int32), ("cell", np.uint32), ("cause", np.uint8),
                              ("pose", np.float32, 6)])
NO_FROZEN_FLOES = np.zeros(0, dtype=FROZEN_FLOE_EVENT)
NO_FROZEN_FLOES.flags.writeable = False  # shared by the events of every step that freezes nothing



@dataclass(frozen=True)
class PlacedTiles:
    """Tiles laid in the ice world, one entry each: flat index in the field, placement index
    in the ice world, template, quarter turns (CCW), south-west corner (m), first floe row
    and row count (rows of one tile are contiguous; a frozen tile has none)."""

    tile: np.ndarray
    placement: np.ndarray
    template: np.ndarray
    quarter_turns: np.ndarray
    corner: np.ndarray  # (k, 2)
    row_start: np.ndarray
    row_count: np.ndarray


def _tile_rows(tiles: TilePlacement, placements: list[int]) -> np.ndarray:
    """Rows of the given placements, concatenated."""
    if not placements:
        return NO_ROWS
    return np.concatenate([tiles.rows(k) for k in placements])


def placed_tiles(tiles: TilePlacement, field_tiles: list[int], placements: list[int]) -> PlacedTiles:
    """The published record of placements (their field tiles given alongside)."""
    return PlacedTiles(
        np.array(field_tiles, dtype=np.int64), np.array(placements, dtype=np.int64),
        np.array([tiles.template[k] for k in placements], dtype=np.int64),
        np.array([tiles.quarter_turns[k] for k in placements], dtype=np.int64),
        np.array([tiles.corner[k] for k in placements], dtype=float).reshape(-1, 2),
        np.array([tiles.row_start[k] for k in placements], dtype=np.int64),
        np.array([tiles.row_count[k] for k in placements], dtype=np.int64))


def apply_swaps(model: WorldModel, data: WorldData, update: SceneUpdate,
                contours: Sequence[np.ndarray] = ()) -> tuple[PlacedTiles, np.ndarray, np.ndarray]:
    """Carry out a scene update in the ice world: place, thaw and freeze tiles. Floes and
    cells that a tile placed or thawed lays under a hull (``contours``: each hull's contour
    points (n, 2), m, in the order of the ice world's hulls) go under it in the next ice
    step, the cells broken (not by the bow).
    Returns the tiles given rows (placed, and thawed with their new rows) and the placement
    indices thawed and frozen."""
    scene, placement = model.scene, data.scene.placement
    reclaim_rows(data.ice)
    new = []
    for tile in update.place.tolist():
        template, turns = tile_layout(scene, tile, data.scene.tile_class[tile])
        placement[tile] = place_tile(model.ice, data.ice, template, tile_corner(scene, tile), turns,
                                     _take_prepared(model, data, tile))
        new.append(placement[tile])
    thawed = [placement[tile] for tile in update.thaw.tolist()]
    frozen = [placement[tile] for tile in update.freeze.tolist()]
    for tile, k in zip(update.thaw.tolist(), thawed):
        thaw_tile(model.ice, data.ice, k, _take_prepared(model, data, tile))
    for k in frozen:
        freeze_tile(data.ice, k)
    if new or thawed or frozen:
        data.live_rows = _tile_rows(data.ice.tiles, [placement[t] for t in data.scene.live.tolist()])
    for hull, contour in zip(data.ice.hulls, contours) if new or thawed else ():
        hull.laid_under = np.union1d(hull.laid_under, _cells_under(model, data, new + thawed, contour))
    return (placed_tiles(data.ice.tiles, update.place.tolist() + update.thaw.tolist(), new + thawed),
            np.array(thawed, dtype=np.int64), np.array(frozen, dtype=np.int64))


def _cells_under(model: WorldModel, data: WorldData, placements: list[int], contour: np.ndarray) -> np.ndarray:
    """Free floes and intact cells of the placements whose outline the hull's waterline
    (contour points (n, 2), m; their convex hull) overlaps: a tile laid, or a frozen tile
    thawed, under the hull where an exercise starts or the ship is moved."""
    st = data.ice.state
    rows = _tile_rows(data.ice.tiles, placements)
    rows = rows[(st.status[rows] == FloeStatus.FREE) | (st.status[rows] == FloeStatus.INTACT)]
    reach = model.ice.radius[st.gcell[rows]][:, None]
    rows = rows[np.all((st.xy[rows] + reach >= contour.min(axis=0)) & (st.xy[rows] - reach <= contour.max(axis=0)),
                       axis=1)]
    if not len(rows):
        return NO_ROWS
    pts, counts = placed_outlines(model.ice, st.gcell[rows], st.xy[rows], st.yaw[rows])
    floes = shapely.polygons(shapely.linearrings(pts, indices=np.repeat(np.arange(len(rows)), counts)))
    return rows[shapely.intersects(floes, shapely.convex_hull(shapely.multipoints(contour)))]


def prepare_switch(model: WorldModel, data: WorldData, tile: int) -> PreparedTile:
    """Start preparing a field tile's switch: a new placement, or the thaw of its frozen one."""
    if data.scene.tile_state[tile] == TileState.FROZEN:
        return prepare_thaw(model.ice, data.ice, data.scene.placement[tile])
    template, turns = tile_layout(model.scene, tile, data.scene.tile_class[tile])
    return prepare_place(model.ice, template, tile_corner(model.scene, tile), turns)


def _take_prepared(model: WorldModel, data: WorldData, tile: int) -> PreparedTile | None:
    """The tile's preparation for its switch now, counting a switch that finds it unfinished."""
    prepared = data.ahead.pop(tile, None)
    if model.scene.settings.prepare_ahead > 0.0 and (prepared is None or not prepared.done):
        data.late_switches += 1
    return prepared


def prepare_ahead(model: WorldModel, data: WorldData, contour: np.ndarray, budget_s: float) -> bool:
    """Build, nearest first and for at most budget_s seconds of wall time, the engine
    objects of the tiles that the hull (contour points (n, 2), m) will soon switch in, and
    drop preparations the hull has left well behind. Touches no physics. True when every
    tile the hull there will switch in is ready."""
    scene = model.scene
    wanted = tiles_to_prepare(scene, data.scene, contour)
    if len(data.ahead) > len(wanted):
        keep = set(tiles_near(contour, scene.radius + 2.0 * scene.settings.prepare_ahead,
                              scene.nx, scene.ny, scene.side).tolist())
        for tile in [t for t in data.ahead if t not in keep]:
            discard_prepared(data.ice, data.ahead.pop(tile))
    if not len(wanted):
        return True
    order = wanted[np.argsort(np.hypot(*(scene.centre(wanted) - contour.mean(axis=0)).T), kind="stable")]
    deadline = time.perf_counter() + budget_s
    for tile in order.tolist():
        if tile not in data.ahead:
            if time.perf_counter() >= deadline:
                return False
            data.ahead[tile] = prepare_switch(model, data, tile)
        prepared = data.ahead[tile]
        while not prepared.done and time.perf_counter() < deadline:
            advance(data.ice, prepared, _PREPARE_CHUNK)
        if not prepared.done:
            return False
    return True


_FREE = int(FloeStatus.FREE)  # for the compiled kernel


def moved_rows(data: WorldData, placed: PlacedTiles) -> np.ndarray:
    """Rows whose pose or status changed in a step: the free floes of the live tiles
    (broken cells included) that moved, or are new or newly free, since they were last
    published, and every row of the tiles placed or thawed in it. Intact cells of live
    tiles do not move, frozen tiles have no rows, and a floe at rest is not sent again
    (in 7/10 pack, two thirds of the free rows: 400 KB a step to every subscriber)."""
    st = data.ice.state
    live = data.live_rows
    moving = live[_newly_moved(live, st.status, st.xy, st.heave, st.yaw, st.roll, st.pitch, st.shown, st.shown_pose)]
    return np.union1d(moving, _tile_rows(data.ice.tiles, placed.placement.tolist())) if len(placed.placement) \
        else moving


@numba.njit(cache=True)
def _newly_moved(rows, status, xy, heave, yaw, roll, pitch, shown, shown_pose):
    """Which rows (n,) are free and not yet published at their pose (x, y, heave, yaw, roll,
    pitch), as ``shown`` and ``shown_pose`` say; marks them published at it. Returns (n,)
    bool."""
    out = np.zeros(len(rows), np.bool_)
    pose = np.empty(6)
    for k in range(len(rows)):
        i = rows[k]
        if status[i] != _FREE:
            continue
        pose[0], pose[1], pose[2], pose[3], pose[4], pose[5] = xy[i, 0], xy[i, 1], heave[i], yaw[i], roll[i], pitch[i]
        same = shown[i]
        for j in range(6):
            same = same and shown_pose[i, j] == pose[j]
        if not same:
            out[k], shown[i] = True, True
            shown_pose[i] = pose
    return out


def warm_up_moved(data: WorldData) -> None:
    """Load ``moved_rows``' compiled kernel (numba compiles or loads it on its first call)."""
    st = data.ice.state
    _newly_moved(data.live_rows[:0], st.status, st.xy, st.heave, st.yaw, st.roll, st.pitch, st.shown, st.shown_pose)


def cracks_published(data: WorldData, placed: PlacedTiles, cracked: np.ndarray) -> np.ndarray:
    """The crack records (``bending.CRACK_EVENT``) a step publishes: the cells it cracked,
    and the cracked cells of the tiles placed or thawed in it (a thawed tile's come back)."""
    rows = np.union1d(cracked, _tile_rows(data.ice.tiles, placed.placement.tolist())) if len(placed.placement) \
        else cracked
    return crack_events(data.ice.state.crack, rows)


def frozen_cracks_of(ice: IceData, placements: list[int]) -> np.ndarray:
    """The published records (``FROZEN_CRACK``) of frozen placements' cracked intact cells."""
    if not placements:  # most steps freeze nothing
        return NO_FROZEN_CRACKS
    return frozen_crack_records(ice.frozen.cracks(k) for k in placements)


def frozen_floes_of(ice: IceData, placements: list[int]) -> np.ndarray:
    """The published records (``FROZEN_FLOE_EVENT``) of frozen placements' floes."""
    if not placements:  # most steps freeze nothing
        return NO_FROZEN_FLOES
    records = [ice.frozen[k] for k in placements]
    out = np.zeros(sum(len(r) for r in records), dtype=FROZEN_FLOE_EVENT)
    out["placement"] = np.repeat(placements, [len(r) for r in records])
    if len(out):
        floes = np.concatenate(records)
        out["cell"], out["cause"] = floes["cell"], floes["cause"]
        out["pose"] = np.column_stack([floes["xy"], floes["heave"], floes["yaw"], floes["roll"], floes["pitch"]])
    return out
