import json
import struct

import numpy as np
import trimesh

from bridge_node.library.gltf import cell_name, export_glb
from bridge_node.library.templates import load_template, save_template, template_path
from sim_core.fracture.tile_template import FractureSettings
from sim_core.material import IceMaterial


def test_stored_and_reloaded_tile_identical(tmp_path, prism_tile):
    path = template_path(tmp_path, 1.0, 0, FractureSettings(), IceMaterial())
    save_template(path, prism_tile)
    back = load_template(path)
    a, b = prism_tile.to_arrays(), back.to_arrays()
    assert a.keys() == b.keys()
    for k in a:
        assert np.array_equal(a[k], b[k]) and np.asarray(a[k]).dtype == np.asarray(b[k]).dtype, k
    assert not list(tmp_path.glob("*.tmp"))


def test_cache_key_changes_with_settings(tmp_path):
    base = template_path(tmp_path, 0.5, 0, FractureSettings(), IceMaterial())
    assert base != template_path(tmp_path, 0.5, 1, FractureSettings(), IceMaterial())
    assert base != template_path(tmp_path, 0.5, 0, FractureSettings(colliders="mesh"), IceMaterial())
    assert base != template_path(tmp_path, 0.5, 0, FractureSettings(), IceMaterial(density=910.0))
    assert base == template_path(tmp_path, 0.5, 0, FractureSettings(variants=5), IceMaterial())


def test_glb_export_reimports_with_cells_volume_and_extras(tmp_path, voronoi3d_tile):
    out = tmp_path / "tile.glb"
    export_glb(voronoi3d_tile, out)
    scene = trimesh.load(out, file_type="glb")
    assert len(scene.geometry) == voronoi3d_tile.n_cells
    total = sum(m.volume for m in scene.geometry.values())
    assert abs(total - voronoi3d_tile.geometry.volume.sum()) < 1e-6 * total
    raw = out.read_bytes()
    header = json.loads(raw[20:20 + struct.unpack("<I", raw[12:16])[0]])
    node = next(nd for nd in header["nodes"] if nd["name"] == cell_name(3))
    assert node["extras"]["cell"] == 3
    assert node["extras"]["collider"] in ("mesh", "sphere")
    assert np.allclose(node["extras"]["seed_point"], voronoi3d_tile.seeds[3])
    assert node["extras"]["sphere_radius_m"] == voronoi3d_tile.sphere_radius[3]
