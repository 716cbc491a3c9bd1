import json
import struct

import numpy as np
import shapely
import trimesh

from bridge_node.library.gltf import cell_name, export_glb
from bridge_node.library.templates import (library_pack_template, load_template, pack_template_path, save_template,
                                           template_path)
from sim_core.fracture.tile_template import FractureSettings
from sim_core.material import IceMaterial
from sim_core.regimes.floe_layout import compile_regimes
from sim_core.regimes.pack_tiles import pack_template
from sim_core.regimes.regime import IceRegion, make_regime


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


def _regimes(concentration, tile_side=100.0):
    """7/10 of thin first-year small floes and grey-white ice cakes (or the cakes at another
    concentration), laid for tiles."""
    regime = make_regime(7, [(4, 87, 4), (concentration, 85, 3)])
    region = IceRegion("pack", shapely.box(0, 0, 800, 800), "ice", regime)
    return compile_regimes([region], region.polygon, seed=5, tile_side=tile_side)


def test_a_floe_field_template_is_stored_once_and_served_as_laid(tmp_path):
    regimes, fracture, ice = _regimes(3), FractureSettings(), IceMaterial()
    path = pack_template_path(tmp_path, regimes, 0, 5, fracture, ice, 24.0)
    assert not path.exists()
    built = library_pack_template(tmp_path, regimes, 0, 5, fracture, ice, 24.0)
    assert path.exists() and len(list(tmp_path.iterdir())) == 1
    mtime = path.stat().st_mtime_ns
    served = library_pack_template(tmp_path, regimes, 0, 5, fracture, ice, 24.0)
    assert path.stat().st_mtime_ns == mtime  # read, not laid again
    laid = pack_template(regimes, 0, 5, fracture, ice, 24.0)
    for a, b in ((built, laid), (served, laid)):
        x, y = a.to_arrays(), b.to_arrays()
        assert x.keys() == y.keys() and all(np.array_equal(x[k], y[k]) for k in x), "not the template as laid"
    assert served.floe_field and served.free_at_start.any() and not served.free_at_start.all()


def test_a_floe_field_template_key_changes_with_what_lays_it(tmp_path):
    regimes, fracture, ice = _regimes(3), FractureSettings(), IceMaterial()
    base = pack_template_path(tmp_path, regimes, 0, 0, fracture, ice, 24.0)
    assert base == pack_template_path(tmp_path, _regimes(3), 0, 0, fracture, ice, 24.0)
    assert base == pack_template_path(tmp_path, regimes, 0, 0, FractureSettings(variants=5), ice, 24.0)
    for other in (pack_template_path(tmp_path, regimes, 0, 1, fracture, ice, 24.0),
                  pack_template_path(tmp_path, _regimes(2), 0, 0, fracture, ice, 24.0),  # another egg code
                  pack_template_path(tmp_path, _regimes(3, 50.0), 0, 0, fracture, ice, 24.0),  # other tiles
                  pack_template_path(tmp_path, regimes, 0, 0, FractureSettings(seed=1), ice, 24.0),
                  pack_template_path(tmp_path, regimes, 0, 0, fracture, IceMaterial(density=910.0), 24.0),
                  pack_template_path(tmp_path, regimes, 0, 0, fracture, ice, 32.0)):  # another ship's beam
        assert other != base


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
