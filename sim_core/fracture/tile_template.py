"""Pre-fractured ice tile templates: static data built once per thickness class (paper §2.1).

A ``TileTemplate`` is the static half of the ice model (like MuJoCo's mjModel): the cells'
geometry, mass, support graph and colliders of one B x B tile. Per-step floe state lives
elsewhere and refers to template cells by index. Templates are deterministic in their seed,
and convert to and from a flat dict of numpy arrays for storage.
"""
from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal

import numpy as np
from pydantic import Field

from sim_core.fracture.colliders import assign_colliders, clear_of_mesh_neighbours, sphere_radii
from sim_core.fracture.fragment_count import seed_count_range
from sim_core.fracture.voronoi_cells import CellGeometry, polygon_area_centroid, prism_cells, voronoi3d_cells
from sim_core.material import IceMaterial
from sim_core.params import Params


class FractureSettings(Params):
    """How tiles are pre-fractured and which colliders their cells get."""

    tile_side: float = Field(100.0, ge=10.0, le=1000.0, description="tile side B, m")
    count_model: Literal["paper", "physical"] = "paper"
    cells: Literal["prism", "voronoi3d"] = "prism"
    colliders: Literal["mesh", "sphere", "hybrid"] = "hybrid"
    mesh_share: float = Field(0.3, ge=0.0, le=1.0, description="hybrid: share of mesh colliders")
    mesh_rule: Literal["poor_fit", "random"] = "poor_fit"
    variants: int = Field(2, ge=1, le=16, description="templates per thickness class")
    seed: int = Field(20231025, ge=0, description="base random seed")


@dataclass(frozen=True)
class TileTemplate:
    """One pre-fractured tile. Arrays are per cell (n rows) unless a CellGeometry field."""

    side: float
    thickness: float
    mode: str
    seed: int
    seeds: np.ndarray  # (n, 3) Voronoi seed points, m (z = h/2 in prism mode)
    geometry: CellGeometry
    mass: np.ndarray  # (n,) kg
    is_sphere: np.ndarray  # (n,) bool: sphere collider (else mesh)
    sphere_radius: np.ndarray  # (n,) m, defined for every cell
    cell_thickness: np.ndarray | None = None  # (n,) m where cells differ (a floe field's types); else ``thickness``
    floe_field: bool = False  # a floe field's template (``sim_core.regimes.pack_tiles``), not level ice
    starts_free: np.ndarray | None = None  # (n,) bool: the cell is a floe of its own from the start; None: none is
    floe: np.ndarray | None = None  # (n,) int32: the pre-fractured floe the cell is part of (-1: none); None: none is

    @property
    def n_cells(self) -> int:
        return self.geometry.n_cells

    @property
    def free_at_start(self) -> np.ndarray:
        """Whether each cell (n,) is laid as a free floe (else intact, level ice)."""
        return np.zeros(self.n_cells, dtype=bool) if self.starts_free is None else self.starts_free

    @property
    def floes(self) -> np.ndarray:
        """Each cell's pre-fractured floe (n,), -1 for cells of none (level ice, free floes)."""
        return np.full(self.n_cells, -1, dtype=np.int32) if self.floe is None else self.floe

    @property
    def thicknesses(self) -> np.ndarray:
        """Each cell's thickness (n,), m."""
        return np.full(self.n_cells, self.thickness) if self.cell_thickness is None else self.cell_thickness

    def to_arrays(self) -> dict[str, np.ndarray]:
        """Flat dict of arrays (for np.savez and friends)."""
        out = {f.name: getattr(self.geometry, f.name) for f in fields(CellGeometry)}
        out.update(
            side=np.float64(self.side), thickness=np.float64(self.thickness),
            mode=np.str_(self.mode), seed=np.int64(self.seed), seeds=self.seeds,
            mass=self.mass, is_sphere=self.is_sphere, sphere_radius=self.sphere_radius,
            cell_thickness=self.thicknesses, floe_field=np.bool_(self.floe_field), starts_free=self.free_at_start,
            floe=self.floes,
        )
        return out

    @classmethod
    def from_arrays(cls, arrays) -> "TileTemplate":
        """Inverse of ``to_arrays``; ``arrays`` is any mapping of name -> array."""
        geometry = CellGeometry(**{f.name: np.asarray(arrays[f.name]) for f in fields(CellGeometry)})
        return cls(
            side=float(arrays["side"]), thickness=float(arrays["thickness"]),
            mode=str(arrays["mode"]), seed=int(arrays["seed"]), seeds=np.asarray(arrays["seeds"]),
            geometry=geometry, mass=np.asarray(arrays["mass"]),
            is_sphere=np.asarray(arrays["is_sphere"]), sphere_radius=np.asarray(arrays["sphere_radius"]),
            cell_thickness=np.asarray(arrays["cell_thickness"]) if "cell_thickness" in arrays else None,
            floe_field=bool(arrays["floe_field"]) if "floe_field" in arrays else False,
            starts_free=np.asarray(arrays["starts_free"]) if "starts_free" in arrays else None,
            floe=np.asarray(arrays["floe"]) if "floe" in arrays else None,
        )


def template_seed(base_seed: int, thickness: float, variant: int) -> int:
    """Deterministic per-template seed from the base seed, thickness (mm) and variant."""
    return int(np.random.SeedSequence([base_seed, int(round(thickness * 1000)), variant]).generate_state(1)[0])


def build_tile(
    thickness: float, seed: int, settings: FractureSettings | None = None,
    material: IceMaterial | None = None,
) -> TileTemplate:
    """Pre-fracture one tile of level ice of the given thickness (m), deterministic in seed."""
    settings = settings or FractureSettings()
    material = material or IceMaterial()
    side, h = settings.tile_side, thickness
    lo, hi = seed_count_range(h, side, settings.count_model, material)
    rng = np.random.default_rng(seed)
    n = int(rng.integers(lo, hi + 1))
    xy = rng.uniform(0.0, side, size=(n, 2))
    if settings.cells == "prism":
        seeds = np.column_stack([xy, np.full(n, 0.5 * h)])
        geometry = prism_cells(xy, side, h)
    else:
        seeds = np.column_stack([xy, rng.uniform(0.0, h, size=n)])
        geometry = voronoi3d_cells(seeds, side, h)
    radius = sphere_radii(geometry.centroid, geometry.verts, geometry.vert_start)
    plan_area = plan_areas(geometry)
    is_sphere = assign_colliders(
        settings.colliders, plan_area, radius, settings.mesh_share, settings.mesh_rule, rng
    )
    radius = clear_of_mesh_neighbours(radius, is_sphere, geometry.centroid, seeds, geometry.adj_pairs)
    return TileTemplate(
        side=side, thickness=h, mode=settings.cells, seed=seed, seeds=seeds, geometry=geometry,
        mass=geometry.volume * material.density, is_sphere=is_sphere, sphere_radius=radius,
    )



def plan_areas(geometry: CellGeometry) -> np.ndarray:
    """Plan-view (footprint) area of every cell, m2."""
    return polygon_area_centroid(geometry.footprint, geometry.foot_start)[0]
