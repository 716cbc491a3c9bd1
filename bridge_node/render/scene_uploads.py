"""The renderer's uploads (``SceneUploads``, a part of ``SceneRenderer``): what changed in
the world view since the last frame goes to the GPU: tiles given other ice by the
instructor, tiles placed, thawed and frozen, the triangles of newly broken floes, the
poses of the rows simulated, a frozen tile's floes once. Split from ``bridge_node.render.renderer`` by responsibility; the renderer's own
attributes are used as they are there."""
from __future__ import annotations

import math
from datetime import datetime, timezone

import moderngl
import numpy as np

from bridge_node.render.floe_buffers import FloeBuffer, FloeCopies, pose_textures, write_entries
from bridge_node.render.meshes import floe_field_layouts
from bridge_node.render.passes.glsl import FROZEN_CRACKED, POSE_WIDTH, UNPLACED_FLOE_FIELD
from bridge_node.render.sky import sky_for
from bridge_node.stream.world_view import Placement, WorldView
from sim_core.frames.geodesy import local_to_geodetic
from sim_core.ice.floes import NO_FROZEN_CRACKS, FloeStatus
from sim_core.scene.switches import NO_FROZEN_FLOES


POSE_NAMES, POSE_UNITS = ("pose_q", "pose_t"), (4, 5)  # the floe pose textures and their units
PATCHES = 61 * 59  # snow patches the floes' tops are given (the floe shader's grid of them)


class SceneUploads:
    """Uploading the world view's changes, for ``SceneRenderer``."""

    def update(self, view: WorldView) -> None:
        """Upload what changed in the view since the last call: tiles given rows (new or
        thawed) and tiles frozen, the triangles of newly broken floes, and the poses of the
        rows that changed; and take the sky of the view's time and place."""
        changes = view.take_changes()
        lat, lon = local_to_geodetic(view.ship.north, view.ship.east, *self.model.origin)
        self.sky = sky_for(datetime.fromtimestamp(view.ship.utc, timezone.utc), lat, lon)  # the exercise clock
        if changes.retiled:
            self._retile(view, np.array(changes.retiled, dtype=np.int64))
        for k in changes.frozen:
            self._freeze(view, k)
        for k in changes.placements:
            self._place(view, k)
        if self._ensure_capacity(view):
            self._upload_rows(view, 0, view.rows)
            for k in self._frozen:
                self._upload_frozen(view, k)
        else:
            self._upload_rows(view, changes.rows_from, changes.rows_to)
            for k in changes.frozen:
                if k in self._frozen:
                    self._upload_frozen(view, k)
        self._append_broken(view, changes.broken)

    def _retile(self, view: WorldView, tiles: np.ndarray) -> None:
        """Take the instructor's new ice of these tiles (a class the model lacks, or a tile
        off the field, is passed over), and redraw those not simulated: the world changes
        only the ice the ship has not met, so a tile placed since is drawn as placed."""
        scene = self.model.scene
        tiles = tiles[(tiles >= 0) & (tiles < len(self.tile_thickness))]
        classes = np.array([view.retiled.get(t, scene.tile_class[t]) for t in tiles.tolist()], dtype=np.int64)
        tiles, classes = tiles[classes < len(scene.class_thickness)], classes[classes < len(scene.class_thickness)]
        self.tile_thickness[tiles] = scene.class_thickness[classes]
        for tile in tiles.tolist():
            self.floe_field_info.pop(tile, None)
        self.floe_field_info.update(floe_field_layouts(self.model, tiles, classes))
        tiles = np.setdiff1d(tiles, [p.tile for p in view.placements.values()])
        for tile, row in zip(tiles.tolist(), self._first_tile_table(tiles)):
            self.tile_info.write(row.tobytes(), viewport=(tile % scene.nx, tile // scene.nx, 1, 1))

    def _write_tile_info(self, p: Placement, first_entry: int, breakable: bool) -> None:
        nx = self.model.scene.nx
        thickness = self.tile_thickness.view("i4")[p.tile]
        flag = int(breakable) or (UNPLACED_FLOE_FIELD if p.tile in self.floe_field_info else 0)
        flag |= self.rubble_bits[p.tile]
        info = np.array([first_entry, p.template | (p.quarter_turns << 16), thickness, flag], "i4")
        self.tile_info.write(info.tobytes(), viewport=(p.tile % nx, p.tile // nx, 1, 1))

    def _drop_floes(self, k: int) -> None:
        for buf in self.tile_floes.pop(k, ()):
            buf.release()
        self.floes.tiles.drop(k)
        self._sides_due.discard(k)

    def _new_floes(self, k: int, p: Placement, first: int) -> None:
        """Empty triangle buffers for tile k, and its uniforms: its first row (negative for
        a frozen tile, whose entries ``_give_entries`` numbers), its snow patches (each floe
        its own, by field tile and cell) and its ice thickness."""
        mesh = self.meshes[p.template]
        if first < 0:  # frozen: indices into the template's vertices, written once
            prog, vbo = self.floes.program, self.mesh_vbos[p.template]
            self.tile_floes[k] = (FloeBuffer(self.ctx, prog, vbo, mesh.index.dtype, 0),
                                  FloeBuffer(self.ctx, prog, vbo, mesh.index.dtype, 0))
        else:
            self.tile_floes[k] = (FloeCopies(self.ctx, self.floes.program, mesh),
                                  FloeCopies(self.ctx, self.floes.program, mesh))
        self.floes.tiles.write(k, first=first, first_floe=0, frozen=first < 0, patch_base=p.tile * 7919 % PATCHES,
                               thickness=self.template_thickness[p.template])

    def _place(self, view: WorldView, k: int) -> None:
        """A tile given rows (laid, or thawed): its cells by row; its floes drawn anew as
        their rows break (a thawed tile's all come as broken)."""
        p = view.placements[k]
        self._drop_floes(k)
        self._frozen.pop(k, None)
        self._grow_drawn(view.rows)
        self._drawn[p.row_start:p.row_start + p.row_count] = False
        self._write_tile_info(p, p.row_start, True)
        self._new_floes(k, p, p.row_start)

    def _freeze(self, view: WorldView, k: int) -> None:
        """A tile frozen: its floes get pose entries of their own, and its cells status
        entries that name each broken cell's floe (numbered from the top of the textures
        down; its rows go to other tiles); its floes' tops are drawn from these, their sides
        made when first needed. A frozen tile without floes or cracks is level ice like the
        unbreakable slab; one with cracks only gets its status entries."""
        p, (floes, cracks) = view.placements[k], self._frozen_records(view, k)
        self._drop_floes(k)
        if not len(floes) and not len(cracks):
            self._frozen.pop(k, None)
            self._write_tile_info(p, 0, False)
            return
        if len(floes):
            self._new_floes(k, p, -1)
        self._give_entries(view, k)
        if not len(floes):  # cracks only: status entries, no floes to draw
            return
        self.tile_floes[k][0].append(self.meshes[p.template].corners(floes["cell"].astype(np.int64), sides=False))
        self._sides_due.add(k)

    def _frozen_records(self, view: WorldView, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Frozen tile k's floes and cracked cells as the view holds them, less any record
        naming a cell its template does not have (a message the stream's bounds let through
        cannot index past the tile's entries)."""
        n_cells = self.model.ice.templates[view.placements[k].template].n_cells
        floes = view.frozen_floes.get(k, NO_FROZEN_FLOES)
        cracks = view.frozen_cracks.get(k, NO_FROZEN_CRACKS)
        return floes[floes["cell"] < n_cells], cracks[cracks["cell"] < n_cells]

    def _give_entries(self, view: WorldView, k: int) -> None:
        """Number frozen tile k's floes and cells after the entries given so far, and point
        its tile table entry and its draw's uniforms at them."""
        p = view.placements[k]
        self._frozen[k] = self._frozen_floes, self._frozen_cells
        self._write_tile_info(p, -1 - self._frozen_cells, True)
        if k in self.tile_floes:  # (a tile frozen with cracks only has no floes to draw)
            self.floes.tiles.write(k, first=-1 - self._frozen_cells, first_floe=self._frozen_floes)
        self._frozen_floes += len(self._frozen_records(view, k)[0])
        self._frozen_cells += self.model.ice.templates[p.template].n_cells

    def _sides(self, view: WorldView, k: int) -> FloeBuffer:
        """Tile k's side faces, made now for a frozen tile that has not needed them yet."""
        if k in self._sides_due:
            self._sides_due.discard(k)
            cells = self._frozen_records(view, k)[0]["cell"].astype(np.int64)
            self.tile_floes[k][1].append(self.meshes[view.placements[k].template].corners(cells, sides=True))
        return self.tile_floes[k][1]

    def _grow_drawn(self, rows: int) -> None:
        if len(self._drawn) < rows:
            self._drawn = np.concatenate([self._drawn, np.zeros(rows - len(self._drawn), bool)])

    def _append_broken(self, view: WorldView, broken: np.ndarray) -> None:
        """Append the triangles of newly broken cells (still broken, in a live tile) to their
        tile's buffers."""
        self._grow_drawn(view.rows)
        new = np.unique(broken)
        new = new[(view.status[new] == FloeStatus.FREE) & ~self._drawn[new]]
        self._drawn[new] = True
        tile, start = self._row_tile(view, new)
        for k in np.unique(tile).tolist():
            cells = new[tile == k] - start[tile == k][0]
            mesh = self.meshes[view.placements[k].template]
            for buf, sides in zip(self.tile_floes[k], (False, True)):
                buf.append(mesh.corners(cells, sides))

    @staticmethod
    def _row_tile(view: WorldView, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Live placement of each row, and that placement's first row (a placement's rows
        are contiguous)."""
        live = sorted((p.row_start, k) for k, p in view.placements.items() if k not in view.frozen and p.row_count)
        starts = np.array([a for a, _ in live], dtype=np.int64)
        at = np.searchsorted(starts, rows, side="right") - 1
        return np.array([k for _, k in live], dtype=np.int64)[at], starts[at]

    def _ensure_capacity(self, view: WorldView) -> bool:
        """Grow the pose and status textures to hold the view's rows (from the first line up)
        and the frozen tiles' entries (from the last line down), those renumbered without the
        entries of tiles since thawed or frozen anew; True if they were (re)made, so that
        everything must be uploaded again."""
        lines = max(1, math.ceil(view.rows / POSE_WIDTH))
        if (lines + math.ceil(self._frozen_floes / POSE_WIDTH) <= self._pose_lines
                and lines + math.ceil(self._frozen_cells / POSE_WIDTH) <= self._status_lines):
            return False
        self._frozen_floes = self._frozen_cells = 0
        for k in list(self._frozen):
            self._give_entries(view, k)
        pose_lines = lines + math.ceil(self._frozen_floes / POSE_WIDTH)
        status_lines = lines + math.ceil(self._frozen_cells / POSE_WIDTH)
        for old in [*self.pose, self.status]:
            if old is not None:
                old.release()
        self._pose_lines = max(pose_lines, 2 * self._pose_lines)
        self._status_lines = max(status_lines, 2 * self._status_lines)
        self.pose = [self.ctx.texture((POSE_WIDTH, self._pose_lines), 4, dtype="f4") for _ in POSE_UNITS]
        self.status = self.ctx.texture((POSE_WIDTH, self._status_lines), 1, dtype="u2")
        for tex in [*self.pose, self.status]:
            tex.filter = moderngl.NEAREST, moderngl.NEAREST
        return True

    def _upload_rows(self, view: WorldView, first_row: int, end_row: int) -> None:
        """Upload the poses and statuses of rows [first_row, end_row), whole texture lines."""
        line0 = first_row // POSE_WIDTH
        r0, r1 = line0 * POSE_WIDTH, end_row
        if r1 <= r0:
            return
        lines = math.ceil((r1 - r0) / POSE_WIDTH)
        n = min(lines * POSE_WIDTH, view.rows - r0)
        texels = np.zeros((len(self.pose), lines * POSE_WIDTH, 4), dtype="f4")
        texels[:, :n] = pose_textures(view.pose[r0:r0 + n])
        viewport = (0, line0, POSE_WIDTH, lines)
        for tex, line in zip(self.pose, texels):
            tex.write(line.tobytes(), viewport=viewport)
        status = np.zeros(lines * POSE_WIDTH, dtype=np.uint16)
        status[:n] = view.status[r0:r0 + n] | view.crack[r0:r0 + n].astype(np.uint16) << 8  # crack label above
        self.status.write(status.tobytes(), viewport=viewport)

    def _upload_frozen(self, view: WorldView, k: int) -> None:
        """Upload a frozen tile's entries: its floes' poses, and its cells' status (1 + the
        place of the cell's floe among the tile's floes; 0 intact; FROZEN_CRACKED | its crack
        label for a cracked intact cell)."""
        (floes, cracks), (first_floe, first_cell) = self._frozen_records(view, k), self._frozen[k]
        n_cells = self.model.ice.templates[view.placements[k].template].n_cells
        status = np.zeros(n_cells, dtype=np.uint16)
        status[floes["cell"]] = 1 + np.arange(len(floes))
        status[cracks["cell"]] = FROZEN_CRACKED | cracks["label"].astype(np.uint16)
        for tex, texels in zip(self.pose, pose_textures(floes["pose"].astype(float)).astype("f4")):
            write_entries(tex, self._pose_lines, first_floe, texels)
        write_entries(self.status, self._status_lines, first_cell, status)

    def floe_memory(self, view: WorldView) -> dict:
        """Bytes kept for the floes of the view, on the GPU and in the view: the index buffers
        of live and of frozen tiles, the frozen tiles' texture entries (entries of tiles since
        thawed included) and the view's frozen records; and the sum per frozen floe."""
        frozen = sum(b.nbytes for k, bufs in self.tile_floes.items() if k in self._frozen for b in bufs)
        live = sum(b.nbytes for k, bufs in self.tile_floes.items() if k not in self._frozen for b in bufs)
        entries = 32 * self._frozen_floes + 2 * self._frozen_cells  # two RGBA32F pose texels; one R16UI status
        records = sum(f.nbytes for f in view.frozen_floes.values())
        n = sum(len(f) for f in view.frozen_floes.values())
        return {"frozen_floes": n, "frozen_index_bytes": frozen, "frozen_entry_bytes": entries,
                "view_frozen_bytes": records, "live_index_bytes": live,
                "bytes_per_frozen_floe": round((frozen + entries + records) / n, 1) if n else None}

    # -- drawing --------------------------------------------------------------------------
