"""Hull contact, conduction cracking and floating floes (paper §2.2, §3.1, §3.2)."""
import math

import numpy as np
import pymunk.batch as pb
import pytest

from sim_core.fracture.tile_template import FractureSettings, build_tile
from sim_core.frames.hull_contour import CONTOUR_POINTS, waterline_contour
from sim_core.ice.breaking import impact_constant
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.model import compile_ice_model
from sim_core.ice.step import HullMotion, ice_step
from sim_core.ice.tiles import break_cells, new_ice_data, place_tile
from sim_core.material import IceMaterial
from sim_core.studies.breaking import channel_and_band, run_breaking

KN = 1852 / 3600
SIDE = 50.0


@pytest.fixture(scope="module")
def runs():
    """Shared experiment runs: 3 x 50 m tiles, the default ship's hull."""
    out = {}
    for setup in ("mesh", "hybrid", "sphere"):
        out[(setup, 3)] = run_breaking(0.5, setup, 3 * KN, tile_side=SIDE, strip_tiles=3, seed=1)
    return out


def test_hull_contour_has_the_papers_34_points():
    c = waterline_contour(150.0, 24.0)
    assert c.shape == (CONTOUR_POINTS, 2) == (34, 2)
    assert c[:, 0].max() == 75.0 and c[:, 0].min() == -75.0 and np.abs(c[:, 1]).max() == 12.0


def test_channel_opened_no_intact_cell_left_in_swept_path(runs):
    r = runs[("sphere", 3)]
    st, m = r.data.state, r.model
    half_beam, centre = 12.0, SIDE / 2
    for i in np.nonzero(st.status == FloeStatus.INTACT)[0]:
        g = st.gcell[i]
        ring = m.outline[m.outline_start[g]:m.outline_start[g + 1]]
        c, s = math.cos(st.yaw[i]), math.sin(st.yaw[i])
        world = ring @ np.array([[c, s], [-s, c]]) + st.xy[i]
        in_path = (np.abs(world[:, 0] - centre) < half_beam - 0.05) & (world[:, 1] > 0) & (world[:, 1] < 3 * SIDE)
        assert not in_path.any(), f"intact cell {i} inside the hull's swept path"
    assert np.any(st.cause == BreakCause.HULL)


def test_thicker_ice_needs_faster_impacts_to_crack():
    mat = IceMaterial()
    tiles = {h: build_tile(h, 1) for h in (0.2, 0.5, 1.0)}
    critical = []
    for h, t in tiles.items():
        k = impact_constant(h, mat)
        critical.append(math.sqrt(k / t.mass.mean()))  # v at which m v^2 = K for a typical floe
    assert critical[0] < critical[1] < critical[2]
    assert critical[0] == pytest.approx(0.3, abs=0.05) and critical[2] == pytest.approx(0.7, abs=0.1)


def test_hull_load_opposes_the_motion(runs):
    for r in runs.values():
        assert r.mean_resistance > 0.0


def test_broken_pieces_float_at_equilibrium_when_left_alone(runs):
    r = runs[("hybrid", 3)]
    far = HullMotion(np.array([SIDE / 2, -5000.0]), 0.5 * math.pi, np.zeros(2), 0.0)
    for _ in range(int(40 / (1 / 30))):
        ice_step(r.model, r.data, (far,), 1 / 30)
    st = r.data.state
    free = st.status == FloeStatus.FREE
    assert free.sum() > 100
    assert np.allclose(st.heave[free], r.model.z_equilibrium[st.gcell[free]], atol=2e-3)
    assert np.abs(st.roll[free]).max() < 2e-3 and np.abs(st.pitch[free]).max() < 2e-3
    assert np.all(np.isfinite(st.xy[free]))


def test_no_floe_accelerates_without_contact_and_energy_decays():
    """Free floes far apart, given velocities: with no contact, every speed only decays."""
    t = build_tile(0.5, 4, FractureSettings(tile_side=40.0, colliders="sphere"))
    m = compile_ice_model([t])
    data = new_ice_data(m, waterline_contour(150, 24), 0.1)
    rows = data.tiles.rows(place_tile(m, data, 0, (0.0, 0.0)))
    keep = rows[::7]  # every 7th cell: free them, take the rest out of the contact space so none touch
    data.contacts.remove(data.state, np.setdiff1d(rows, keep))
    break_cells(data, keep, BreakCause.HULL)
    rng = np.random.default_rng(2)
    data.contacts.set_velocity(data.state, keep, rng.uniform(-0.05, 0.05, (len(keep), 2)), np.zeros(len(keep)))
    far = HullMotion(np.array([0.0, -9000.0]), 0.0, np.zeros(2), 0.0)
    speeds, energies = [], []
    for _ in range(300):
        rep = ice_step(m, data, (far,), 1 / 30)
        assert len(rep.broken_by_contact) == 0
        v = data.state.vel[keep]
        speeds.append(np.linalg.norm(v, axis=1))
        energies.append(0.5 * (m.mass[data.state.gcell[keep]] * (v**2).sum(axis=1)).sum())
    speeds = np.array(speeds)
    assert np.all(np.diff(speeds, axis=0) <= 1e-12)
    assert np.all(np.diff(energies) < 0) and energies[-1] < 0.7 * energies[0]


def test_a_floe_the_hull_has_left_is_not_among_its_contacts():
    """Chipmunk keeps a separated pair's contact for a few steps, with no points and no
    impulse: the hull's contacts (what strikes floes, sends them under and loads the hull)
    leave such a pair out. The hull strikes the floe with its side, so that the floe stays
    afloat (one sent under leaves the engine with its contacts, ``TileBodies.sink``)."""
    t = build_tile(0.5, 4, FractureSettings(tile_side=40.0, colliders="sphere"))
    m = compile_ice_model([t])
    data = new_ice_data(m, waterline_contour(150, 24), 0.1)
    rows = data.tiles.rows(place_tile(m, data, 0, (0.0, 0.0)))
    one = rows[[len(rows) // 2]]
    data.contacts.remove(data.state, np.setdiff1d(rows, one))
    break_cells(data, one, BreakCause.HULL)
    x, y = data.state.xy[one[0]]
    hull = np.array([x, y - 12.0 - data.contacts.extent[data.state.gcell[one[0]]] - 0.3])  # its side short of it
    hull_pairs, v = [], 2.0
    for _ in range(90):  # sideways into the floe, then away once it is struck
        hull += (0.0, v / 30)
        ice_step(m, data, (HullMotion(hull.copy(), 0.0, np.array([0.0, v]), 0.0),), 1 / 30)
        buf = pb.Buffer()
        pb.get_space_arbiters(data.contacts.space, pb.ArbiterFields.BODY_A_ID | pb.ArbiterFields.BODY_B_ID
                              | pb.ArbiterFields.CONTACT_COUNT, buf)
        held = np.frombuffer(buf.int_buf(), dtype=np.uintp).reshape(-1, 3)
        touching = len(data.contacts.read_contacts(data.state).with_hull()[0])
        hull_pairs.append((len(held), int(held[:, 2].sum()) if len(held) else 0, touching))
        v = -3.0 if touching else v
    assert any(pts > 0 and touching == 1 for _, pts, touching in hull_pairs)  # it was struck...
    separated = [touching for held, pts, touching in hull_pairs if held and not pts]
    assert separated and not any(separated)  # ...and once apart, its kept contact is no contact


def test_band_measure_on_known_profiles():
    y = np.arange(1.0, 40.0, 2.0)
    broken = (y < 15).astype(float)
    pushed = ((y > 12) & (y < 15)).astype(float)
    channel, band = channel_and_band(np.column_stack([y, broken, pushed]), half_beam=12.0)
    assert channel == pytest.approx(30.0, abs=2.0)
    assert band == pytest.approx(2.0, abs=0.01)  # one 2 m bin (y = 13) fully pushed-broken beyond B/2


def test_voronoi3d_templates_rejected_by_dynamics():
    t = build_tile(1.0, 1, FractureSettings(cells="voronoi3d", tile_side=20.0))
    with pytest.raises(ValueError, match="prism"):
        compile_ice_model([t])


def test_floes_pushed_under_the_hull_surface_and_right_themselves(runs):
    r = runs[("sphere", 3)]
    st = r.data.state
    assert st.submerged.any()  # the stern still covers the end of the strip
    onward = HullMotion(np.array([SIDE / 2, 400.0]), 0.5 * math.pi, np.array([0.0, 3 * KN]), 0.0)
    for _ in range(int(30 / (1 / 30))):
        ice_step(r.model, r.data, (onward,), 1 / 30)
    assert not st.submerged.any()  # the hull has gone: everything surfaced
    by_hull = (st.cause == BreakCause.HULL) & (st.status == FloeStatus.FREE)
    g = st.gcell[by_hull]
    assert np.allclose(st.heave[by_hull], r.model.z_equilibrium[g], atol=0.05)
    assert np.abs(st.roll[by_hull]).max() < 0.25  # all were tilted 0.25 rad going under
