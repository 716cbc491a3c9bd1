"""Geometric validity of pre-fractured tiles, checked against independent computations."""
import numpy as np
import pytest
import trimesh
from pydantic import ValidationError
from scipy.spatial import cKDTree

from sim_core.fracture.colliders import assign_colliders
from sim_core.fracture.tile_template import FractureSettings, TileTemplate, build_tile


@pytest.fixture(params=["prism", "voronoi3d"])
def tile(request, prism_tile, voronoi3d_tile) -> TileTemplate:
    return prism_tile if request.param == "prism" else voronoi3d_tile


def cell_mesh(tile, i):
    g = tile.geometry
    return trimesh.Trimesh(
        g.verts[g.vert_start[i]:g.vert_start[i + 1]], g.tris[g.tri_start[i]:g.tri_start[i + 1]],
        process=False,
    )


def test_volumes_sum_to_slab(tile):
    slab = tile.side * tile.side * tile.thickness
    assert abs(tile.geometry.volume.sum() - slab) / slab < 1e-9


def test_every_cell_watertight_convex_outward_with_its_volume(tile):
    for i in range(tile.n_cells):
        m = cell_mesh(tile, i)
        assert m.is_watertight and m.is_winding_consistent and m.is_convex, i
        assert m.volume > 0
        assert m.volume == pytest.approx(tile.geometry.volume[i], rel=1e-9)
        assert np.allclose(m.center_mass, tile.geometry.centroid[i], atol=1e-7)


def test_cells_do_not_overlap_and_fill_the_slab(tile):
    """Every random point of the slab lies inside exactly one cell (half-space test)."""
    rng = np.random.default_rng(0)
    pts = rng.uniform([0, 0, 0], [tile.side, tile.side, tile.thickness], size=(3000, 3))
    hits = np.zeros(len(pts), dtype=int)
    g = tile.geometry
    for i in range(tile.n_cells):
        v = g.verts[g.vert_start[i]:g.vert_start[i + 1]]
        f = g.tris[g.tri_start[i]:g.tri_start[i + 1]]
        normal = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        inside = ((pts[:, None, :] - v[f[:, 0]][None]) * normal[None]).sum(axis=2) < 1e-9
        hits += inside.all(axis=1)
    assert np.all(hits == 1)


def test_adjacency_symmetric_and_accounts_for_every_face(tile):
    """Each cell's surface = its shared faces (from the adjacency) + its faces on the slab
    boundary; and the adjacency matrix is symmetric with unique pairs."""
    g, n = tile.geometry, tile.n_cells
    pairs = g.adj_pairs
    assert np.all(pairs[:, 0] < pairs[:, 1])
    assert len(np.unique(pairs, axis=0)) == len(pairs)
    adj = np.zeros((n, n))
    adj[pairs[:, 0], pairs[:, 1]] = g.adj_area
    adj = adj + adj.T
    shared = adj.sum(axis=1)
    # a pair shares a face: at least three common vertices (a face is a polygon)
    for a, b in pairs[:: max(1, len(pairs) // 200)]:
        va = {tuple(v) for v in np.round(g.verts[g.vert_start[a]:g.vert_start[a + 1]], 6)}
        vb = {tuple(v) for v in np.round(g.verts[g.vert_start[b]:g.vert_start[b + 1]], 6)}
        assert len(va & vb) >= 3, (a, b)
    lim = np.array([tile.side, tile.side, tile.thickness])
    for i in range(n):
        m = cell_mesh(tile, i)
        c = m.triangles_center
        on_box = np.any((np.abs(c) < 1e-7) | (np.abs(c - lim) < 1e-7), axis=1)
        boundary = m.area_faces[on_box].sum()
        assert shared[i] + boundary == pytest.approx(m.area, rel=1e-6), i


def test_no_two_spheres_overlap(tile):
    c, r = tile.geometry.centroid, tile.sphere_radius
    assert np.all(r > 0)
    i, j = np.array(sorted(cKDTree(c).query_pairs(2 * r.max()))).T
    d = np.linalg.norm(c[i] - c[j], axis=1)
    assert np.all(r[i] + r[j] <= d + 1e-12)


def test_collider_setups_reproduce_the_papers_three_arrangements(prism_tile):
    area, r = prism_tile.geometry.volume / prism_tile.thickness, prism_tile.sphere_radius
    assert not assign_colliders("mesh", area, r).any()
    assert assign_colliders("sphere", area, r).all()
    hybrid = assign_colliders("hybrid", area, r, mesh_share=0.3, rule="poor_fit")
    assert (~hybrid).sum() == round(0.3 * len(area))
    fit = np.pi * r**2 / area
    assert fit[~hybrid].max() <= fit[hybrid].min()  # mesh where spheres fit worst
    rnd = assign_colliders("hybrid", area, r, 0.3, "random", np.random.default_rng(1))
    assert (~rnd).sum() == round(0.3 * len(area)) and not np.array_equal(rnd, hybrid)


def test_same_seed_gives_identical_tile_and_other_seed_differs():
    a, b = build_tile(0.5, 11).to_arrays(), build_tile(0.5, 11).to_arrays()
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    c = build_tile(0.5, 12).to_arrays()
    assert not np.array_equal(a["seeds"], c["seeds"])


def test_voronoi3d_mode_gives_non_vertical_faces(voronoi3d_tile):
    g = voronoi3d_tile.geometry
    v, f = g.verts, g.tris + np.repeat(g.vert_start[:-1], np.diff(g.tri_start))[:, None]
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    nz = np.abs(n[:, 2]) / np.linalg.norm(n, axis=1)
    assert np.any((nz > 0.05) & (nz < 0.95))  # slanted fracture faces exist


def test_unknown_collider_setup_rejected():
    with pytest.raises(ValueError, match="allowed"):
        assign_colliders("capsule", np.ones(3), np.ones(3))
    with pytest.raises(ValidationError, match="'prism' or 'voronoi3d'"):
        FractureSettings(cells="tetra")


def test_hybrid_spheres_stay_clear_of_mesh_neighbours(prism_tile):
    """No sphere collider reaches into a neighbouring cell that has a mesh collider."""
    from shapely import Point, Polygon

    g, t = prism_tile.geometry, prism_tile
    assert t.is_sphere.any() and (~t.is_sphere).any()
    for a, b in g.adj_pairs:
        for i, j in ((a, b), (b, a)):
            if t.is_sphere[i] and not t.is_sphere[j]:
                disk = Point(*g.centroid[i, :2]).buffer(t.sphere_radius[i], quad_segs=64)
                poly = Polygon(g.footprint[g.foot_start[j]:g.foot_start[j + 1]])
                assert disk.intersection(poly).area < 1e-6 * poly.area
