"""Floating (paper §2.3): submerged volume by triangle clipping, and heave/roll/pitch."""
import math

import numpy as np
import pytest
import trimesh

from sim_core.fracture.tile_template import build_tile
from sim_core.ice.buoyancy import posed_vertices, submerged_volume_centre, submerged_volume_centre_reference
from sim_core.ice.model import compile_ice_model, vertical_substeps
from sim_core.ice.vertical import vertical_step


@pytest.fixture(scope="module")
def model():
    return compile_ice_model([build_tile(0.5, 3)])


def test_submerged_volume_matches_trimesh_capped_slice(model):
    rng = np.random.default_rng(0)
    cells = rng.choice(len(model.mass), 60, replace=False)
    zc = rng.uniform(-0.4, 0.4, len(cells))
    roll, pitch = rng.uniform(-0.6, 0.6, len(cells)), rng.uniform(-0.6, 0.6, len(cells))
    vol, centre = submerged_volume_centre(model.tris, model.tri_start, cells, zc, roll, pitch)
    for k, c in enumerate(cells):
        tris = posed_vertices(model.tris[model.tri_start[c]:model.tri_start[c + 1]], zc[k], roll[k], pitch[k])
        mesh = trimesh.Trimesh(tris.reshape(-1, 3), np.arange(3 * len(tris)).reshape(-1, 3))
        mesh.merge_vertices()
        cell_volume = model.mass[c] / model.material.density
        under = trimesh.intersections.slice_mesh_plane(mesh, [0, 0, -1], [0, 0, 0], cap=True)
        expected = under.volume if len(under.faces) else 0.0
        assert abs(vol[k] - expected) <= 1e-9 * cell_volume
        if expected > 1e-6 * cell_volume:
            assert np.allclose(centre[k], under.center_mass, atol=1e-9 * math.sqrt(cell_volume))


def test_numba_kernel_matches_numpy_reference(model):
    rng = np.random.default_rng(1)
    cells = rng.integers(0, len(model.mass), 500)
    args = (model.tris, model.tri_start, cells, rng.uniform(-0.5, 0.5, 500),
            rng.uniform(-1, 1, 500), rng.uniform(-1, 1, 500))
    v1, c1 = submerged_volume_centre(*args)
    v2, c2 = submerged_volume_centre_reference(*args)
    assert np.allclose(v1, v2, rtol=0, atol=1e-12) and np.allclose(c1, c2, atol=1e-12)


def test_fully_under_and_fully_above():
    t = build_tile(0.5, 3)
    m = compile_ice_model([t])
    cells = np.array([0, 1])
    vol, _ = submerged_volume_centre(m.tris, m.tri_start, cells, np.array([-5.0, 5.0]), np.zeros(2), np.zeros(2))
    assert vol[0] == pytest.approx(t.geometry.volume[0], rel=1e-12) and vol[1] == 0.0


def simulate(model, cells, heave, roll, pitch, seconds, dt=1 / 60):
    n = len(cells)
    rows = np.arange(n)
    state = [np.array(heave, float), np.array(roll, float), np.array(pitch, float),
             np.zeros(n), np.zeros(n), np.zeros(n)]
    mat = model.material
    history = []
    for _ in range(int(seconds / dt)):
        vertical_step(rows, cells, model.tris, model.tri_start, model.mass, model.inertia, model.damping,
                      model.settings.heave_added_mass, mat.water_density * mat.gravity, mat.gravity,
                      *state, dt, vertical_substeps(model, dt))
        history.append([a.copy() for a in state[:3]])
    return state, history


def test_flat_prism_settles_at_archimedes_draft(model):
    cells = np.arange(0, 40)
    state, _ = simulate(model, cells, np.full(40, 0.3), np.zeros(40), np.zeros(40), 30.0)
    h = 0.5
    draft = h * model.material.density / model.material.water_density
    assert np.allclose(state[0], 0.5 * h - draft, atol=1e-4)  # centre of mass above water
    assert np.allclose(state[0], model.z_equilibrium[cells], atol=1e-4)


def test_tilted_floe_rights_itself(model):
    cells = np.arange(10)
    state, history = simulate(model, cells, model.z_equilibrium[cells], np.full(10, 0.3), np.full(10, -0.25), 30.0)
    assert np.all(np.abs(state[1]) < 1e-3) and np.all(np.abs(state[2]) < 1e-3)
    roll = np.array([h[1] for h in history])
    assert np.abs(roll[: len(roll) // 10]).max() > 0.05  # it really was tilted


def test_floe_never_sinks_or_flies_away(model):
    rng = np.random.default_rng(5)
    cells = rng.integers(0, len(model.mass), 50)
    _, history = simulate(model, cells, rng.uniform(-1.0, 1.0, 50), rng.uniform(-0.5, 0.5, 50),
                          rng.uniform(-0.5, 0.5, 50), 120.0)
    heave = np.array([h[0] for h in history])
    assert np.all(np.isfinite(heave))
    assert heave.min() > -1.5 and heave.max() < 1.5  # h = 0.5 m floes stay at the surface
    assert np.allclose(heave[-1], model.z_equilibrium[cells], atol=1e-3)
