"""The static half of the ice world (like MuJoCo's mjModel): compiled tile templates, floe
mass properties, hydrostatics, colliders and breaking capacities, per template cell.

All templates' cells are concatenated into one global cell index ("gcell"); per-step floe
state refers to cells by that index. Geometry is stored about each cell's centre of mass.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydantic import Field

from sim_core.csr import gather_ranges, offsets
from sim_core.fracture.tile_template import TileTemplate
from sim_core.ice.breaking import RIDE_UP_SHARE, WEDGE_COEFFICIENT, impact_constant, ride_up_load, static_capacity
from sim_core.ice.drift import DEVIATION_DEG, WIND_FACTOR
from sim_core.ice.wide_floes import WideFloes, compile_wide_floes
from sim_core.material import IceMaterial
from sim_core.params import Params


class IceDynamicsSettings(Params):
    """Contact, drag, floating and breaking constants of the ice dynamics."""

    drag_time_s: float = Field(20.0, gt=0.5, le=600.0, description="planar velocity e-folding time in water, s")
    wind_drift_factor: float = Field(WIND_FACTOR, ge=0.0, le=0.05,
                                     description="free drift: broken ice speed / wind speed (Nansen's rule)")
    wind_drift_angle_deg: float = Field(DEVIATION_DEG, ge=0.0, le=60.0,
                                        description="free drift: degrees to the right of the wind (left in the "
                                                    "southern hemisphere)")
    field_drift: bool = Field(False, description="the whole ice field drifts with the current and the wind's free "
                              "drift, as one body of ice (pack: its floes, channels, frozen tiles and regions go "
                              "with it); off: the level ice is fast and only the broken floes drift")
    wide_floes_move: bool = Field(True, description="a floe wider than the beam moves as one body once a hull comes "
                                  "near, until the hull breaks it cell by cell (``sim_core.ice.compound_floes``); off: "
                                  "it is held as level ice is. In 3/10 medium and 4/10 small floes the 60 Hz main "
                                  "job's tick p99 was 14.8 ms and 14.9 ms in two 15-minute runs on 2 cores "
                                  "(docs/benchmarks/main-job.md)")
    propeller_wash: bool = Field(False, description="the propeller's jet drags the floes in it "
                                 "(``sim_core.ship.propeller_jet``); off by default: the floes it keeps "
                                 "moving cost the world step 40-70 % more over a long run")
    heave_damping_ratio: float = Field(0.3, ge=0.0, le=2.0)
    roll_pitch_damping_ratio: float = Field(0.3, ge=0.0, le=2.0)
    heave_added_mass: float = Field(0.5, ge=0.0, le=3.0, description="C_a: added mass / mass in heave")
    ice_friction: float = Field(0.3, ge=0.0, le=1.0, description="ice-ice friction coefficient")
    wedge_coefficient: float = Field(WEDGE_COEFFICIENT, gt=0.0, le=2.0, description="C_w in F_s = C_w sigma_f h^2")
    ride_up_share: float = Field(RIDE_UP_SHARE, gt=0.0, le=1.0,
                                 description="share of its weight a floe riding onto an edge rests on it")
    solver_iterations: int = Field(10, ge=1, le=100)
    collision_slop: float = Field(0.01, ge=0.0, le=0.5, description="allowed overlap, m")
    rest_far_floes: bool = Field(True, description="floes at rest far from the hull leave the dynamic set")
    rest_distance: float = Field(
        150.0, ge=20.0, le=5000.0,
        description="m from the hull's reference point beyond which a floe at rest may leave the dynamic set; "
                    "it rejoins within 0.8 of this (or nearer than the hull's reach plus a floe and 10 m, "
                    "whichever is farther)")
    rest_speed: float = Field(0.02, gt=0.0, le=1.0,
                              description="m/s: a floe slower than this (centre, and its rim turning) is at rest; "
                                          "a contact that would give a resting floe this speed wakes it")
    rest_after_s: float = Field(1.0, ge=0.0, le=60.0, description="s a floe must stay at rest before it leaves")
    rest_per_step: int = Field(200, ge=1, le=1_000_000, description="floes a step may take out of the dynamic set")
    swap_objects_per_step: int = Field(
        800, ge=1, le=1_000_000, description="engine objects a step switches in for tile swaps")
    swap_removal_work: int = Field(
        125_000, ge=1000, le=100_000_000,
        description="removals x (cached contacts + 140) a step may spend switching tiles out: Chipmunk walks "
                    "every cached contact for each removal, and a removal costs about 140 such visits besides")
    rest_search_work: int = Field(
        600_000, ge=1000, le=100_000_000,
        description="entries of the dynamic-body array Chipmunk may search in a step for floes coming to rest "
                    "(each one that turns static is looked up there)")


@dataclass(frozen=True)
class IceModel:
    """Compiled templates. Arrays indexed by global cell g unless noted."""

    material: IceMaterial
    settings: IceDynamicsSettings
    templates: tuple[TileTemplate, ...]
    template_start: np.ndarray  # (n_templates + 1,) first gcell of each template
    floe_field: np.ndarray  # (n_templates,) bool: a floe field's template
    starts_free: np.ndarray  # (G,) bool: the cell is laid as a free floe (a floe field's), not intact
    centroid: np.ndarray  # (G, 3) in the template's tile frame, m
    tris: np.ndarray  # (T, 3, 3) triangles about the centroid, m
    tri_start: np.ndarray  # (G + 1,)
    outline: np.ndarray  # (P, 2) plan-view outline about the centroid, m
    outline_start: np.ndarray  # (G + 1,)
    seed_offset: np.ndarray  # (G, 2) the cell's Voronoi seed relative to its centroid, m
    mass: np.ndarray  # (G,) kg
    inertia: np.ndarray  # (G, 3) Ixx, Iyy, Izz about the centroid, kg m2
    is_sphere: np.ndarray  # (G,) bool
    radius: np.ndarray  # (G,) sphere collider radius, m
    thickness: np.ndarray  # (G,) m
    plan_area: np.ndarray  # (G,) plan-view area, m2
    z_equilibrium: np.ndarray  # (G,) floating height of the centroid above the water, m
    stiffness: np.ndarray  # (G, 3) hydrostatic heave N/m, roll and pitch N m/rad
    damping: np.ndarray  # (G, 3) heave N s/m, roll and pitch N m s/rad
    k_impact: np.ndarray  # (G,) impact breaking constant, N s * m/s
    edge_capacity: np.ndarray  # (G,) quasi-static breaking load F_s of the cell as an edge, N
    ride_load: np.ndarray  # (G,) vertical load of the cell as a floe riding onto an edge, N
    omega_max: float  # highest heave/roll/pitch natural frequency, rad/s
    wide: WideFloes  # the floe fields' floes wider than the beam, by global floe


def _second_moments(tris: np.ndarray, owner: np.ndarray, n: int) -> np.ndarray:
    """Volume second moments C_ij = int x_i x_j dV (n, 3, 3) of closed meshes about their
    origin, by signed tetrahedra (0, a, b, c): C = V/20 (sum p p^T + s s^T), s = a + b + c."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    vol = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    s = a + b + c
    out = np.zeros((n, 3, 3))
    for i in range(3):
        for j in range(3):
            term = a[:, i] * a[:, j] + b[:, i] * b[:, j] + c[:, i] * c[:, j] + s[:, i] * s[:, j]
            out[:, i, j] = np.bincount(owner, vol * term / 20.0, minlength=n)
    return out


def compile_ice_model(templates: list[TileTemplate], material: IceMaterial | None = None,
                      settings: IceDynamicsSettings | None = None) -> IceModel:
    """Precompute everything the ice dynamics needs from prism-mode templates."""
    material = material or IceMaterial()
    settings = settings or IceDynamicsSettings()
    for t in templates:
        if t.mode != "prism":
            raise ValueError("contact dynamics need prism cells: voronoi3d cells overlap in plan view")
    counts = np.array([t.n_cells for t in templates])
    template_start = offsets(counts)
    n = int(counts.sum())
    geo = [t.geometry for t in templates]
    centroid = np.vstack([g.centroid for g in geo])
    tri_counts = np.concatenate([np.diff(g.tri_start) for g in geo])
    tri_start = offsets(tri_counts)
    owner = np.repeat(np.arange(n), tri_counts)
    tris = np.vstack([
        g.verts[g.tris + np.repeat(g.vert_start[:-1], np.diff(g.tri_start))[:, None]] for g in geo
    ]) - centroid[owner][:, None, :]
    out_counts = np.concatenate([np.diff(g.foot_start) for g in geo])
    outline_start = offsets(out_counts)
    outline = np.vstack([g.footprint for g in geo]) - centroid[np.repeat(np.arange(n), out_counts), :2]
    thickness = np.concatenate([t.thicknesses for t in templates]) if templates else np.zeros(0)
    mass = np.concatenate([t.mass for t in templates])
    cov = _second_moments(tris, owner, n) * material.density
    inertia = np.column_stack([cov[:, 1, 1] + cov[:, 2, 2], cov[:, 0, 0] + cov[:, 2, 2], cov[:, 0, 0] + cov[:, 1, 1]])
    # prism cells: waterplane = plan outline; its second moments from the volume ones / h
    plan_area = mass / (material.density * thickness)
    rg = material.water_density * material.gravity
    stiffness = np.column_stack([rg * plan_area, rg * cov[:, 1, 1] / (material.density * thickness),
                                 rg * cov[:, 0, 0] / (material.density * thickness)])
    heave_mass = mass * (1.0 + settings.heave_added_mass)
    damping = np.column_stack([
        2.0 * settings.heave_damping_ratio * np.sqrt(stiffness[:, 0] * heave_mass),
        2.0 * settings.roll_pitch_damping_ratio * np.sqrt(stiffness[:, 1] * inertia[:, 0]),
        2.0 * settings.roll_pitch_damping_ratio * np.sqrt(stiffness[:, 2] * inertia[:, 1]),
    ])
    omega = np.sqrt(np.column_stack([stiffness[:, 0] / heave_mass, stiffness[:, 1] / inertia[:, 0],
                                     stiffness[:, 2] / inertia[:, 1]]))
    draft = thickness * material.density / material.water_density
    return IceModel(
        material=material, settings=settings, templates=tuple(templates), template_start=template_start,
        floe_field=np.array([t.floe_field for t in templates], dtype=bool),
        starts_free=np.concatenate([t.free_at_start for t in templates]) if templates else np.zeros(0, dtype=bool),
        centroid=centroid,
        tris=np.ascontiguousarray(tris), tri_start=tri_start, outline=outline, outline_start=outline_start,
        seed_offset=np.vstack([t.seeds[:, :2] for t in templates]) - centroid[:, :2],
        mass=mass, inertia=inertia, is_sphere=np.concatenate([t.is_sphere for t in templates]),
        radius=np.concatenate([t.sphere_radius for t in templates]), thickness=thickness, plan_area=plan_area,
        z_equilibrium=0.5 * thickness - draft, stiffness=stiffness, damping=damping,
        k_impact=impact_constant(thickness, material, settings.wedge_coefficient),
        edge_capacity=static_capacity(thickness, material, settings.wedge_coefficient),
        ride_load=ride_up_load(mass, material, settings.ride_up_share),
        omega_max=float(omega.max()) if n else 0.0, wide=compile_wide_floes(templates),
    )


def vertical_substeps(model: IceModel, dt: float) -> int:
    """Sub-steps that keep omega * h <= 0.2 for the semi-implicit heave/roll/pitch update."""
    return max(1, math.ceil(model.omega_max * dt / 0.2))


def placed_outlines(model: IceModel, gcell: np.ndarray, at: np.ndarray,
                    angle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Plan outlines of cells ``gcell`` (n,) with their centroids at (n, 2) m and turned by
    (n,) rad CCW: all points (P, 2), m, and each outline's point count (n,)."""
    start, stop = model.outline_start[gcell], model.outline_start[gcell + 1]
    counts = stop - start
    owner = np.repeat(np.arange(len(gcell)), counts)
    ring = model.outline[gather_ranges(start, stop)]
    c, s = np.cos(angle)[owner], np.sin(angle)[owner]
    return np.column_stack([c * ring[:, 0] - s * ring[:, 1], s * ring[:, 0] + c * ring[:, 1]]) + at[owner], counts


def placed_centroids(model: IceModel, template: int, corner: tuple[float, float] | np.ndarray,
                     quarter_turns: int) -> tuple[np.ndarray, float]:
    """World centroids (n, 2) m of a template's cells laid with the tile's south-west corner
    at corner (m), turned by quarter turns CCW about the tile's centre, and their yaw, rad."""
    t, g0 = model.templates[template], int(model.template_start[template])
    k = quarter_turns % 4
    c, s = round(math.cos(k * math.pi / 2)), round(math.sin(k * math.pi / 2))
    rel = model.centroid[g0:g0 + t.n_cells, :2] - 0.5 * t.side
    home = np.column_stack([c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1]]) + 0.5 * t.side
    return home + np.asarray(corner, dtype=float), k * math.pi / 2

