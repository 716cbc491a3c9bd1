"""Export a tile template to glTF binary (GLB) for Blender or Unity, via trimesh.

One mesh per cell, named ``cell_NNNNN``; the node's extras carry the cell id, seed point,
volume, mass and collider (type and sphere radius). Coordinates: tile frame, metres, z up
(glTF viewers that expect y up show the tile lying on its side).
"""
from __future__ import annotations

from pathlib import Path

import trimesh

from bridge_node.common.output_files import write_output
from sim_core.fracture.tile_template import TileTemplate


def cell_name(i: int) -> str:
    return f"cell_{i:05d}"


def tile_scene(template: TileTemplate) -> trimesh.Scene:
    """A trimesh Scene holding one mesh per cell with its metadata."""
    g = template.geometry
    scene = trimesh.Scene()
    for i in range(template.n_cells):
        mesh = trimesh.Trimesh(
            g.verts[g.vert_start[i]:g.vert_start[i + 1]], g.tris[g.tri_start[i]:g.tri_start[i + 1]],
            process=False,
        )
        extras = {
            "cell": i,
            "seed_point": [float(x) for x in template.seeds[i]],
            "volume_m3": float(g.volume[i]),
            "mass_kg": float(template.mass[i]),
            "collider": "sphere" if template.is_sphere[i] else "mesh",
            "sphere_radius_m": float(template.sphere_radius[i]),
        }
        scene.add_geometry(mesh, node_name=cell_name(i), geom_name=cell_name(i), metadata=extras)
    scene.metadata.update(
        {"thickness_m": template.thickness, "side_m": template.side, "mode": template.mode,
         "seed": template.seed}
    )
    return scene


def export_glb(template: TileTemplate, path: str | Path) -> None:
    """Write the tile as a .glb file."""
    write_output(path, tile_scene(template).export(file_type="glb"), "--export")
