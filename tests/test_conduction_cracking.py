"""Conduction cracking judged on medians over seeds (issue 12): the paper's §3.1 thickness
trend, the §3.2 collider ordering, the speed dependence; the load bound that lets thick
edges hold; ``icebridge experiment breaking --seeds``."""
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import run_cli

from sim_core.fracture.tile_template import FractureSettings, build_tile
from sim_core.ice.breaking import breaks, impact_constant, ride_up_load, static_capacity
from sim_core.ice.floes import BreakCause
from sim_core.ice.model import compile_ice_model
from sim_core.material import IceMaterial
from sim_core.studies.breaking import conduction_per_length, run_breaking_seeds

KN = 1852 / 3600
SEEDS = [1, 2, 3]
STRIP = {"tile_side": 50.0, "strip_tiles": 3}  # 3 x 50 m tiles, the default ship's hull
THICKNESS = (0.2, 0.5, 1.0)


@pytest.fixture(scope="module")
def medians():
    """Medians over SEEDS: hybrid at 3 kn for every thickness; mesh, sphere and hybrid at
    8 kn in 0.2 m ice, where there is conduction cracking to order."""
    out = {("hybrid", 3, h): run_breaking_seeds(h, "hybrid", 3 * KN, SEEDS, **STRIP) for h in THICKNESS}
    for setup, kn in (("mesh", 3), ("sphere", 3), ("hybrid", 8)):
        out[(setup, kn, 0.2)] = run_breaking_seeds(0.2, setup, kn * KN, SEEDS, **STRIP)
    return out


def test_conduction_cracking_falls_with_thickness(medians):
    count = [medians[("hybrid", 3, h)].median("contact_count") for h in THICKNESS]
    area = [medians[("hybrid", 3, h)].median("contact_area") for h in THICKNESS]
    assert count[0] > 30  # per 100 m: in 0.2 m ice many pieces beside the channel crack
    assert count[0] > count[1] > count[2]
    assert area[0] > area[1] > area[2]
    assert count[2] <= count[0] / 3


def test_collider_ordering_on_medians(medians):
    mesh, hybrid, sphere = (medians[(s, 3, 0.2)] for s in ("mesh", "hybrid", "sphere"))
    for metric in ("contact_count", "contact_area", "band_width"):
        assert mesh.median(metric) > hybrid.median(metric) > sphere.median(metric), metric
    assert mesh.median("channel_width") > 1.5 * sphere.median("channel_width")  # mesh cracks far too wide


def test_faster_ship_cracks_more_on_medians(medians):
    slow, fast = medians[("hybrid", 3, 0.2)], medians[("hybrid", 8, 0.2)]
    for metric in ("contact_count", "contact_area", "band_width"):
        assert fast.median(metric) > slow.median(metric), metric


def test_channel_in_beams_and_band_in_pieces(medians):
    for m in medians.values():
        for r in m.runs:
            assert r.channel_beams == pytest.approx(r.channel_width / 24.0)
            assert r.band_pieces == pytest.approx(r.band_width / r.piece_diameter)
        assert m.median("channel_beams") > 0.95  # the hull opens at least its beam
    diameters = [medians[("hybrid", 3, h)].median("piece_diameter") for h in THICKNESS]
    assert diameters[0] < diameters[2]  # thicker ice, larger pieces (paper §2.1)


def test_conduction_measure_counts_contact_cells_in_the_window():
    home = np.array([[0.0, 10.0], [5.0, 30.0], [9.0, 60.0], [2.0, 40.0]])  # m; the window is y 25-75 m
    cause = np.array([BreakCause.CONTACT, BreakCause.CONTACT, BreakCause.CONTACT, BreakCause.HULL])
    count, area = conduction_per_length(home, cause, np.array([1.0, 2.0, 4.0, 8.0]), 25.0, 75.0)
    assert count == pytest.approx(4.0) and area == pytest.approx(12.0)  # 2 cells, 6 m2 in 50 m


def test_squeezed_floe_cannot_break_an_edge_stronger_than_its_ride_up_load():
    """A floe jammed against the edge by the hull takes an impulse as large as the hull
    needs: the energy test alone would always break the edge, the load test decides."""
    mat = IceMaterial()
    squeeze = np.array([1e9])  # N s
    for h, expected in ((0.2, True), (1.0, False)):
        mass = np.array([900.0 * h * 5.0])  # a 5 m2 floe
        k, fs, load = impact_constant(h, mat), static_capacity(h, mat), ride_up_load(mass, mat)
        assert bool(breaks(squeeze, np.zeros(1), mass, k, load, fs)[0]) is expected
        assert not breaks(np.array([1.0]), np.array([0.01]), mass, k, load + fs, fs)[0]  # energy still needed
    model = compile_ice_model([build_tile(0.5, 3, FractureSettings(tile_side=20.0))], mat)
    assert np.allclose(model.ride_load, 0.5 * model.mass * mat.gravity)
    assert np.allclose(model.edge_capacity, static_capacity(0.5, mat))
    assert np.allclose(model.plan_area * 0.5 * mat.density, model.mass)


def test_breaking_command_prints_medians_and_seeds(tmp_path):
    r = run_cli("experiment", "breaking", "--thickness", "0.2", "--colliders", "sphere", "--speed", "8",
                "--tile-side", "30", "--strip-tiles", "1", "--seeds", "2", "--json", "--out", str(tmp_path))
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    config, = out["configurations"]
    assert len(out["seeds"]) == 2 == len(set(out["seeds"])) and config["seeds"] == out["seeds"]
    assert [run["seed"] for run in config["runs"]] == out["seeds"]
    for key in ("contact_cells_per_100m", "contact_area_m2_per_100m", "channel_beams", "band_width_m", "band_pieces"):
        per_seed = [run[key] for run in config["runs"]]
        assert config["median"][key] == pytest.approx(np.median(per_seed), abs=0.1), key  # both rounded
    assert Path(config["picture"]).stat().st_size > 10_000 and Path(out["summary_plot"]).exists()


@pytest.mark.parametrize("args, message", [
    (["--seeds", "0"], "--seeds 0 is outside the allowed range [1, 50]"),
    (["--seeds", "three"], "argument --seeds: invalid int value: 'three'"),
])
def test_breaking_command_bad_seeds_are_clear_errors(args, message, tmp_path):
    r = run_cli("experiment", "breaking", *args, "--out", str(tmp_path))
    assert r.returncode == 2 and message in r.stderr
    assert "Traceback" not in r.stderr


def test_floes_jammed_against_thick_ice_go_under_instead_of_stopping_the_ship(tmp_path):
    """In 1.0 m ice the edge holds against squeezed floes (the load test); such a floe is
    forced under the edge, out of planar contact, so the jam does not load the hull: the
    default ship at full ahead keeps going (it stopped at 0.3 kn before floes went under)."""
    from conftest import exercise_config

    from bridge_node.node.world_setup import build_world, start_world
    from sim_core.world import step

    cfg = exercise_config(tmp_path / "tiles", 300.0, 400.0, 50.0, start_north=-60.0)
    cfg = cfg.model_copy(update={"ice_field": cfg.ice_field.model_copy(update={"thickness": 1.0})})
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    went_under = 0
    for _ in range(2400):  # 80 s at 30 Hz
        events = step(model, data, 1 / 30)
        went_under = max(went_under, int(np.count_nonzero(data.ice.state.submerged)))
    assert data.ship.eta[0] > 60.0  # well into the ice: its edge was at 0 m
    assert events.ship.speed_over_ground > 1.5 * KN
    assert went_under > 0
