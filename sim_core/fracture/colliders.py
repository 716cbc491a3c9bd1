"""Collider assignment for pre-fractured cells (paper §2.2): mesh, sphere or hybrid.

A mesh collider is the convex cell itself (its plan-view footprint for planar contact): it
fits exactly, so neighbours share faces and a push travels far. A sphere collider sits on
the cell centroid; the paper starts from an enclosing sphere and shrinks radii until no two
spheres overlap, which leaves gaps between neighbours and damps the push. In a hybrid tile a
sphere is also kept clear of its mesh-collider neighbours (``clear_of_mesh_neighbours``), so
that freeing a cell never starts from an overlap.

Hybrid rules (which cells get a mesh collider, ``mesh_share`` of them):
``poor_fit``  the cells a sphere represents worst: lowest ratio of the sphere's cross-section
              to the cell's plan area (elongated, angular cells). Default.
``random``    a seeded random subset.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

COLLIDER_SETUPS = ("mesh", "sphere", "hybrid")
MESH_RULES = ("poor_fit", "random")


def sphere_radii(centroid: np.ndarray, verts: np.ndarray, vert_start: np.ndarray) -> np.ndarray:
    """Sphere radius per cell (m): the enclosing radius about the centroid, shrunk to half the
    distance to the nearest other centroid, so that no two spheres overlap
    (r_i + r_j <= d_ij/2 + d_ij/2 = d_ij)."""
    cell = np.repeat(np.arange(len(centroid)), np.diff(vert_start))
    dist = np.linalg.norm(verts - centroid[cell], axis=1)
    enclosing = np.maximum.reduceat(dist, vert_start[:-1])
    if len(centroid) < 2:
        return enclosing
    nearest, _ = cKDTree(centroid).query(centroid, k=2)
    return np.minimum(enclosing, 0.5 * nearest[:, 1])


def assign_colliders(
    setup: str, plan_area: np.ndarray, radius: np.ndarray, mesh_share: float = 0.5,
    rule: str = "poor_fit", rng: np.random.Generator | None = None,
) -> np.ndarray:
    """Boolean mask, True where a cell gets a sphere collider, False for a mesh collider."""
    n = len(plan_area)
    if setup == "mesh":
        return np.zeros(n, dtype=bool)
    if setup == "sphere":
        return np.ones(n, dtype=bool)
    if setup != "hybrid":
        raise ValueError(f"unknown collider setup {setup!r}; allowed: {', '.join(COLLIDER_SETUPS)}")
    n_mesh = int(round(mesh_share * n))
    if rule == "poor_fit":
        fit = np.pi * radius**2 / plan_area
        mesh_cells = np.argsort(fit, kind="stable")[:n_mesh]
    elif rule == "random":
        mesh_cells = (rng or np.random.default_rng(0)).permutation(n)[:n_mesh]
    else:
        raise ValueError(f"unknown hybrid rule {rule!r}; allowed: {', '.join(MESH_RULES)}")
    is_sphere = np.ones(n, dtype=bool)
    is_sphere[mesh_cells] = False
    return is_sphere


def clear_of_mesh_neighbours(
    radius: np.ndarray, is_sphere: np.ndarray, centroid: np.ndarray, seeds: np.ndarray,
    adj_pairs: np.ndarray,
) -> np.ndarray:
    """Shrink sphere radii (m) so no sphere reaches into a neighbouring mesh-collider cell.

    The face two Voronoi cells share lies on the bisector plane of their seeds, and cell j
    lies wholly beyond it, so r_i <= distance(centroid_i, bisector(s_i, s_j)) suffices.
    """
    out = radius.copy()
    for a, b in ((adj_pairs[:, 0], adj_pairs[:, 1]), (adj_pairs[:, 1], adj_pairs[:, 0])):
        sel = is_sphere[a] & ~is_sphere[b]
        i, j = a[sel], b[sel]
        normal = seeds[j] - seeds[i]
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        mid = 0.5 * (seeds[i] + seeds[j])
        dist = ((mid - centroid[i]) * normal).sum(axis=1)
        np.minimum.at(out, i, dist)
    return out
