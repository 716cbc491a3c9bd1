"""The station's picture of the exercise, made from the stream's ``WorldView`` about ten
times a second: the ship panel's values, the environment, the live floes as typed arrays
(global cell and pose), every placed tile's broken cells (and a frozen tile's floes) with a
version that changes only when they do, the own ship's track, and the event log. Each
browser gets only what changed since the last frame it was sent (``ClientCursor``)."""
from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, field

import numpy as np

from bridge_node.station.events import EventLog
from bridge_node.station.geometry import laid_runs
from bridge_node.station.wire import pack
from bridge_node.stream.world_view import WorldView
from sim_core.frames.units import KNOT
from sim_core.ice.floes import FloeStatus
from sim_core.world import WorldModel

TRACK_EVERY_S = 1.0  # simulated s between track points
TRACK_JUMP_M = 50.0  # a move longer than this between two points breaks the line (a reposition)
TRACK_MAX = 20_000  # points kept; the oldest half is thinned when full


@dataclass
class TileEntry:
    """One placed tile as the page draws it: ``meta`` (placement, template, turns, corner,
    frozen), its broken cells and, for a frozen tile, their floes' poses (x, y, yaw)."""

    version: int
    meta: dict
    cells: np.ndarray
    floes: np.ndarray


@dataclass
class Frame:
    """One update of the picture (what every browser is sent a part of)."""

    number: int
    header: dict
    floe_cell: np.ndarray  # int32 global cells of the live tiles' free floes
    floe_pose: np.ndarray  # float32 (n, 3): x east, y north (m), yaw (rad CCW)
    tiles: dict[int, TileEntry]
    track: np.ndarray  # float32 (m, 2), NaN rows break the line
    track_epoch: int
    events: tuple[dict, ...]  # the log as it was (the feed thread goes on adding to it)
    scene_epoch: int


@dataclass
class ClientCursor:
    """What one browser has been sent: tile versions, track points, events."""

    tiles: dict[int, int] = field(default_factory=dict)
    scene_epoch: int = -1
    track_epoch: int = -1
    track_sent: int = 0
    event_sent: int = 0


def ship_panel(view: WorldView) -> dict:
    """The ship's values in the bridge's units."""
    s = view.ship
    x, y, n = (float(v) for v in view.ice_load)
    return {
        "east": s.east, "north": s.north, "heading": s.heading,
        "latitude_deg": math.degrees(s.latitude), "longitude_deg": math.degrees(s.longitude),
        "heading_deg": math.degrees(s.heading), "cog_deg": math.degrees(s.course_over_ground),
        "sog_kn": s.speed_over_ground / KNOT, "stw_kn": s.speed_longitudinal / KNOT,
        "rot_deg_min": math.degrees(s.rate_of_turn) * 60.0, "rudder_deg": math.degrees(s.rudder_angle),
        "rpm": s.shaft_rps * 60.0, "ice_resistance_kn": s.ice_resistance / 1e3,
        "ice_load_kn": [x / 1e3, y / 1e3, n / 1e3],
        "utc": dt.datetime.fromtimestamp(s.utc, dt.timezone.utc).isoformat(timespec="seconds"),
        "searchlights": [[light.on, light.bearing, light.elevation] for light in s.searchlights],
    }


def environment_panel(view: WorldView) -> dict:
    """The instructor's environment in the bridge's units."""
    e = view.environment
    return {"visibility_m": e.visibility, "wind_kn": e.wind_speed / KNOT, "wind_from_deg": math.degrees(e.wind_from),
            "current_kn": e.current_speed / KNOT, "current_to_deg": math.degrees(e.current_to), "frozen": e.frozen}


def traffic_list(view: WorldView) -> list[dict]:
    """The other vessels (a few), with their speed in knots."""
    return [{"id": int(v["id"]), "x": float(v["x"]), "y": float(v["y"]), "heading": float(v["heading"]),
             "speed_kn": float(v["speed"]) / KNOT, "length": float(v["length"]), "beam": float(v["beam"])}
            for v in view.traffic]


class Picture:
    """Makes frames from a ``WorldView``; keeps the tile versions, the track and the log."""

    def __init__(self, model: WorldModel) -> None:
        self.template_start = np.asarray(model.ice.template_start, dtype=np.int64)
        self.grid = model.scene.nx, model.scene.ny
        self._laid: tuple[int, list[list[int]]] = (0, [])  # the view's retiled version, and its runs
        self.tiles: dict[int, TileEntry] = {}
        self.log = EventLog()
        self._track = np.full((TRACK_MAX, 2), np.nan, dtype=np.float32)
        self._track_n, self.track_epoch, self._track_time = 0, 0, -math.inf
        self._number = 0
        self.scene_epoch = 0  # changes when the tiles start afresh (a new subscriber's snapshot)

    def reset(self) -> None:
        """Forget the tiles (the next frame names all of the view's); the track and log stay."""
        self.tiles = {}
        self.scene_epoch += 1

    def add_track_point(self, view: WorldView) -> None:
        """A point of the own ship's track every ``TRACK_EVERY_S`` simulated s; a jump (a
        reposition) breaks the line; a rewind of the clock (a new exercise) starts anew."""
        s = view.ship
        if view.time < self._track_time:
            self._track_n, self._track_time, self.track_epoch = 0, -math.inf, self.track_epoch + 1
        if view.time - self._track_time < TRACK_EVERY_S:
            return
        point = np.array([s.east, s.north], dtype=np.float32)
        if self._track_n and np.hypot(*(point - self._track[self._track_n - 1])) > TRACK_JUMP_M:
            self._append(np.array([np.nan, np.nan], dtype=np.float32))
        self._append(point)
        self._track_time = view.time

    def _append(self, point: np.ndarray) -> None:
        if self._track_n == TRACK_MAX:  # thin the older half: every second point of it
            half = TRACK_MAX // 2
            kept = np.concatenate([self._track[:half:2], self._track[half:]])
            self._track[:len(kept)] = kept
            self._track_n, self.track_epoch = len(kept), self.track_epoch + 1
        self._track[self._track_n] = point
        self._track_n += 1

    def _tile_entry(self, view: WorldView, k: int) -> tuple[dict, np.ndarray, np.ndarray]:
        p = view.placements[k]
        frozen = k in view.frozen
        meta = {"k": k, "tile": p.tile, "template": p.template, "turns": p.quarter_turns,
                "corner": list(p.corner), "frozen": frozen}
        if frozen:
            records = view.frozen_floes.get(k)
            if records is None or not len(records):
                return meta, np.zeros(0, np.uint32), np.zeros((0, 3), np.float32)
            return meta, records["cell"].astype(np.uint32), records["pose"][:, [0, 1, 3]].astype(np.float32)
        status = view.status[p.row_start:p.row_start + p.row_count]
        return meta, np.flatnonzero(status == FloeStatus.FREE).astype(np.uint32), np.zeros((0, 3), np.float32)

    def _update_tiles(self, view: WorldView) -> None:
        """New versions of the tiles that changed: every live tile is looked at (a few
        tens); a frozen one only when it has just frozen (its floes no longer move)."""
        just_frozen = set(view.take_changes().frozen)
        for k in view.placements:
            old = self.tiles.get(k)
            if old is not None and old.meta["frozen"] and k in view.frozen and k not in just_frozen:
                continue
            meta, cells, floes = self._tile_entry(view, k)
            if old is None or old.meta != meta or not np.array_equal(old.cells, cells) or \
                    not np.array_equal(old.floes, floes):
                self.tiles[k] = TileEntry((old.version + 1) if old else 0, meta, cells, floes)

    def _free_floes(self, view: WorldView) -> tuple[np.ndarray, np.ndarray, list[list[int]]]:
        """Global cells and poses (x, y, yaw) of the live tiles' free floes, tile by tile,
        and each tile's [placement, floe count] (the page redraws only the tiles whose
        floes moved)."""
        cells, poses, tiles = [], [], []
        for k, p in view.placements.items():
            if k in view.frozen or not p.row_count:
                continue
            rows = p.row_start + np.flatnonzero(view.status[p.row_start:p.row_start + p.row_count] == FloeStatus.FREE)
            if len(rows):
                cells.append(self.template_start[p.template] + rows - p.row_start)
                poses.append(view.pose[rows][:, [0, 1, 3]])
                tiles.append([k, len(rows)])
        if not cells:
            return np.zeros(0, np.int32), np.zeros((0, 3), np.float32), []
        return np.concatenate(cells).astype(np.int32), np.concatenate(poses).astype(np.float32), tiles

    def _laid_runs(self, view: WorldView) -> list[list[int]]:
        """The instructor's ice as runs (``laid_runs``), made again only when it changed."""
        if self._laid[0] != view.retiled_version:
            self._laid = view.retiled_version, laid_runs(view.retiled, *self.grid)
        return self._laid[1]

    def frame(self, view: WorldView, extra: dict) -> Frame:
        """A frame of the view as it is now; ``extra`` joins the header (stream and
        control health, alarms)."""
        self._update_tiles(view)
        self.add_track_point(view)
        floe_cell, floe_pose, floe_tiles = self._free_floes(view)
        self._number += 1
        header = {"type": "frame", "seq": view.seq, "time": view.time, "ship": ship_panel(view), "floe_tiles": floe_tiles,
                  "environment": environment_panel(view), "traffic": traffic_list(view),
                  "ice_offset": [round(float(v), 3) for v in view.ice_offset],
                  "laid": self._laid_runs(view),
                  "counts": {"free": len(floe_cell), "frozen_floes": int(sum(len(t.cells) for t in self.tiles.values()
                                                                             if t.meta["frozen"])),
                             "tiles_live": sum(not t.meta["frozen"] for t in self.tiles.values()),
                             "tiles_frozen": sum(t.meta["frozen"] for t in self.tiles.values())},
                  **extra}
        return Frame(self._number, header, floe_cell, floe_pose, dict(self.tiles),
                     self._track[:self._track_n].copy(), self.track_epoch, self.log.since(0), self.scene_epoch)


def message_for(frame: Frame, cursor: ClientCursor) -> bytes:
    """The binary message of a frame for one browser: what it has not been sent yet (tiles
    changed, new track points, new events) and the whole of what moves (floes, ship)."""
    scene_reset = cursor.scene_epoch != frame.scene_epoch
    if scene_reset:
        cursor.tiles, cursor.scene_epoch = {}, frame.scene_epoch
    changed = [t for k, t in frame.tiles.items() if cursor.tiles.get(k) != t.version]
    for t in changed:
        cursor.tiles[t.meta["k"]] = t.version
    if cursor.track_epoch != frame.track_epoch:
        cursor.track_epoch, cursor.track_sent = frame.track_epoch, 0
        reset = True
    else:
        reset = False
    track = frame.track[cursor.track_sent:]
    cursor.track_sent = len(frame.track)
    events = [e for e in frame.events if e["id"] > cursor.event_sent]
    cursor.event_sent = events[-1]["id"] if events else cursor.event_sent
    header = {**frame.header, "tiles": [{**t.meta, "cells": len(t.cells), "floes": len(t.floes)} for t in changed],
              "scene_reset": scene_reset, "track_reset": reset, "events": events}
    empty_u, empty_f = np.zeros(0, np.uint32), np.zeros(0, np.float32)
    return pack(header, {
        "floe_cell": frame.floe_cell, "floe_pose": frame.floe_pose,
        "tile_cells": np.concatenate([t.cells for t in changed]) if changed else empty_u,
        "tile_floes": np.concatenate([t.floes.ravel() for t in changed]) if changed else empty_f,
        "track": track})
