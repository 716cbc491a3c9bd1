"""The own ship's mesh (hull and superstructure) for the channels: loaded from the GLB that
the ship file names (``[look] model_glb``), or generated from the particulars, so that its
waterline is the hull contour the ice feels and the bridge stands under the bridge eye.

Frame: the ship frame, metres: x forward from midship, y to starboard, z up from the
waterline. Other vessels reuse the mesh, scaled to their length and beam.
"""
from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np
import trimesh

from bridge_node.common.errors import UserError
from bridge_node.common.input_files import MIB, read_input
from sim_core.ship.particulars import ShipParticulars

HULL, BOOT, DECK, HOUSE, MAST = (0.50, 0.10, 0.08), (0.12, 0.12, 0.13), (0.33, 0.37, 0.34), (0.86, 0.86, 0.82), \
    (0.85, 0.62, 0.10)
HATCH, GEAR, FUNNEL, CRANE = (0.42, 0.20, 0.15), (0.16, 0.17, 0.18), (0.75, 0.14, 0.10), (0.80, 0.80, 0.76)
HATCH_GAP_M, HATCH_H_M = 3.0, 1.6  # m: between hatch covers; their height above the deck
MAX_GLB_BYTES = 256 * MIB  # a ship model far larger than any a bridge view needs
BOTTOM_M = -2.0  # m: the hull is drawn this deep (floes sliding under it show in the water)
EYE_ABOVE_FLOOR_M = 1.7  # m: the bridge eye above the bridge deck
SHEER = 0.25  # the deck's rise at the stem over the freeboard
BULWARK_M = 1.2  # m: the bulwark around the deck edge (from the bridge, it outlines the bow)


class ShipModelError(ValueError):
    """A ship's GLB that cannot be used; the message names the ship file's key and value."""


def _faces(tris: np.ndarray, colour: tuple[float, float, float]) -> trimesh.Trimesh:
    """Unshared triangles (n, 3, 3) of one colour (each vertex its own, so vertex and face
    colours agree in a GLB)."""
    mesh = trimesh.Trimesh(tris.reshape(-1, 3), np.arange(len(tris) * 3).reshape(-1, 3), process=False)
    mesh.visual.face_colors = np.tile(np.round(np.array([*colour, 1.0]) * 255).astype(np.uint8), (len(tris), 1))
    return mesh


def _box(lo: tuple[float, float, float], hi: tuple[float, float, float], colour: tuple[float, float, float]
         ) -> trimesh.Trimesh:
    box = trimesh.creation.box(bounds=np.array([lo, hi], dtype=float))
    return _faces(box.vertices[box.faces], colour)


def _oriented(tris: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """The triangles wound so that their normals point away from `centre`."""
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    inward = np.einsum("ij,ij->i", n, tris.mean(axis=1) - centre) < 0.0
    tris = tris.copy()
    tris[inward] = tris[inward][:, ::-1]
    return tris


def default_ship(particulars: ShipParticulars, contour: np.ndarray, freeboard: float) -> trimesh.Trimesh:
    """A hull lofted from the waterline contour (m, ship frame) to a sheered deck, the stem
    raked at the particulars' stem angle (the rake at most 5 % of the length), a bulwark
    round the deck, a boot topping below the waterline, a deckhouse whose top is the bridge deck under the bridge
    eye, bridge wings 1 m beyond the beam, a funnel, and the deck gear of ``deck_gear``."""
    L, B = particulars.length, particulars.beam
    rise = np.clip((contour[:, 0] - 0.2 * L) / (0.3 * L), 0.0, 1.0) ** 2  # 0 amidships, 1 at the stem
    rake = min(freeboard / math.tan(math.radians(particulars.ice.stem_angle_deg)), 0.05 * L)
    deck = np.column_stack([contour[:, 0] + rake * rise, contour[:, 1], freeboard * (1.0 + SHEER * rise)])
    water = np.column_stack([contour, np.zeros(len(contour))])
    bottom = np.column_stack([contour * 0.97, np.full(len(contour), BOTTOM_M)])
    centre = np.array([0.0, 0.0, 0.5 * freeboard])

    def band(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
        a, b = lower, np.roll(lower, -1, axis=0)
        c, d = upper, np.roll(upper, -1, axis=0)
        return _oriented(np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]), centre)

    middle = np.array([deck[:, 0].mean(), 0.0, deck[:, 2].mean()])
    top = np.stack([np.repeat(middle[None], len(deck), 0), deck, np.roll(deck, -1, axis=0)], 1)
    top = _oriented(top, middle - [0.0, 0.0, 1.0])
    bx, bz = particulars.look.bridge_eye
    floor = bz - EYE_ABOVE_FLOOR_M
    rail = deck + [0.0, 0.0, BULWARK_M]
    parts = [_faces(band(water, deck), HULL), _faces(band(bottom, water), BOOT), _faces(top, DECK),
             _faces(band(deck, rail), HULL),
             _box((bx - 16.0, -0.4 * B, freeboard - 0.5), (bx + 2.0, 0.4 * B, floor), HOUSE),
             _box((bx - 1.5, -0.5 * B - 1.0, floor - 0.4), (bx + 1.5, 0.5 * B + 1.0, floor), DECK),
             _box((bx - 13.0, -2.5, floor), (bx - 8.0, 2.5, floor + 6.0), FUNNEL)]
    return trimesh.util.concatenate(parts + deck_gear(L, B, freeboard, bx - 16.0, bx + 2.0))


def deck_gear(length: float, beam: float, freeboard: float, house_aft: float, house_fore: float
              ) -> list[trimesh.Trimesh]:
    """What stands on a general cargo ship's weather deck (ship frame, m): a breakwater at the
    forecastle's after end, windlasses and a foremast with its signal yard on the forecastle,
    and hatch covers with a stowed deck crane between each pair along the holds forward and
    aft of the deckhouse (between ``house_aft`` and ``house_fore``), port and starboard by turns. All of it lies below the
    sight line from the bridge to the sea two ship lengths ahead (SOLAS V/22.1.1) but the
    foremast and the cranes' posts, each a blind sector of a degree or two (V/22.1.2)."""
    fore = 0.5 * length - 0.12 * length  # the forecastle's after end
    deck = freeboard + 0.1
    parts = [_box((fore - 1.0, -0.4 * beam, deck), (fore, 0.4 * beam, deck + 2.0), HULL),  # breakwater
             _box((fore + 6.0, -0.5, deck), (fore + 6.6, 0.5, deck + 14.0), MAST),
             _box((fore + 6.0, -3.0, deck + 11.0), (fore + 6.6, 3.0, deck + 11.4), MAST)]  # signal yard
    for side in (-1.0, 1.0):
        parts.append(_box((fore + 2.0, side * 3.5 - 1.2, deck), (fore + 4.0, side * 3.5 + 1.2, deck + 1.4), GEAR))
    holds = [(house_fore + 4.0, fore - 3.0), (-0.5 * length + 14.0, house_aft - 4.0)]
    for start, end in holds:
        count = max(1, round((end - start) / 20.0))
        size = (end - start - (count - 1) * HATCH_GAP_M) / count
        for k in range(count):
            x0 = start + k * (size + HATCH_GAP_M)
            parts.append(_box((x0, -0.36 * beam, deck), (x0 + size, 0.36 * beam, deck + HATCH_H_M), HATCH))
            if k:  # a crane post in the gap, port and starboard by turns, its jib stowed fore and aft
                post, y = x0 - 0.5 * HATCH_GAP_M, (-1.0) ** k * 0.3 * beam
                parts += [_box((post - 1.0, y - 1.0, deck), (post + 1.0, y + 1.0, deck + 7.0), CRANE),
                          _box((post, y - 0.4, deck + 6.0), (post + 0.9 * size, y + 0.4, deck + 6.8), CRANE)]
    return parts


def load_ship(particulars: ShipParticulars, contour: np.ndarray, freeboard: float) -> trimesh.Trimesh:
    """The ship's mesh: its GLB (an absolute path or one relative to the working directory)
    if the ship file names one, else the generated default."""
    name = particulars.look.model_glb
    if name is None:
        return default_ship(particulars, contour, freeboard)
    where = f"ships/{particulars.name}.toml: look.model_glb = {name!r}"
    path = Path(name)
    if path.suffix.lower() != ".glb":
        raise ShipModelError(f"{where}: expected a .glb file")
    try:
        data = read_input(path, "ship model", MAX_GLB_BYTES, where)
    except UserError as exc:
        raise ShipModelError(str(exc)) from None
    try:
        mesh = trimesh.load(io.BytesIO(data), file_type="glb", force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds on a damaged file
        raise ShipModelError(f"{where}: not a GLB trimesh can read ({type(exc).__name__}: {exc})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ShipModelError(f"{where}: the file holds no triangles")
    return mesh


def ship_triangles(mesh: trimesh.Trimesh) -> np.ndarray:
    """Vertex data of the mesh's triangles: position 3f, face normal 3f, colour 3f (its face
    colours; a textured mesh gives its main colour)."""
    visual = mesh.visual if isinstance(mesh.visual, trimesh.visual.ColorVisuals) else mesh.visual.to_color()
    colour = np.asarray(visual.face_colors, dtype=float)[:, :3] / 255.0
    out = np.zeros((len(mesh.faces), 3, 9), dtype="f4")
    out[:, :, :3] = mesh.vertices[mesh.faces]
    out[:, :, 3:6] = mesh.face_normals[:, None]
    out[:, :, 6:] = colour[:, None]
    return out.reshape(-1, 9)


# COLREG rule 21 sectors: (centre, half width) in degrees from the bow, + to starboard
MASTHEAD, STARBOARD, PORT, STERN = (0.0, 112.5), (56.25, 56.25), (-56.25, 56.25), (180.0, 67.5)
WHITE, GREEN, RED = (1.0, 0.97, 0.88), (0.15, 1.0, 0.45), (1.0, 0.12, 0.08)


def nav_lights(particulars: ShipParticulars, bounds: np.ndarray) -> np.ndarray:
    """The navigation lights of a ship with this mesh's bounds ((2, 3), ship frame, m):
    masthead on top over the forward part, sidelights at the bridge wings' ends, stern
    light at the stern. Rows of position 3f, colour 3f, sector centre and half width (rad
    from the bow, + to starboard)."""
    (x0, y0, _), (x1, y1, z1) = bounds
    bx, bz = particulars.look.bridge_eye
    floor = bz - EYE_ABOVE_FLOOR_M
    rise = 1.0  # m: the lanterns stand this far clear of the surfaces they are on
    rows = [((x0 + 0.88 * (x1 - x0), 0.0, z1 + rise), WHITE, MASTHEAD), ((bx, y1, floor + rise), GREEN, STARBOARD),
            ((bx, y0, floor + rise), RED, PORT), ((x0 - rise, 0.0, 0.5 * floor), WHITE, STERN)]
    return np.array([[*pos, *colour, *np.radians(sector)] for pos, colour, sector in rows], dtype="f4")


def glb_bytes(mesh: trimesh.Trimesh) -> bytes:
    """The mesh as a GLB file (ship frame, z up), e.g. the generated default as a start for a
    ship's own model."""
    return mesh.export(file_type="glb")
