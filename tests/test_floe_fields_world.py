"""Floe fields in the running world (issue 26, item 2 in part): a floe-field region's tiles
are laid from pack templates, open water between the floes. A floe narrower than the beam
is a free floe from the start, which the hull pushes aside or under; one wider than the beam
is the pre-fracture cut to the floe, which splits along its cells when rammed. Floes laid
under the hull go under it, and the channels draw the floes and the water between them,
near the ship and far from it."""
import numpy as np
import pytest
import shapely
from conftest import exercise_config, region_world

from bridge_node.node.floe_field_setup import field_regions, lay_floe_fields
from bridge_node.node.world_setup import field_tile_classes
from bridge_node.render.channels import ChannelSet
from bridge_node.render.classes import CLASS_INDEX, class_of_pixels
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.stream.world_view import WorldView
from sim_core.ice.floes import BreakCause, FloeStatus
from sim_core.ice.tiles import broken_counts
from sim_core.regimes.pack_tiles import MIN_FLOE_AREA
from sim_core.regimes.regime import MIN_FLOE_SIZE
from sim_core.regimes.settings import RegionSettings
from sim_core.scene.scene import tile_layout
from sim_core.world import snapshot, step

PACK = {"name": "pack", "polygon_m": [[0.0, 0.0], [400.0, 0.0], [400.0, 600.0], [0.0, 600.0]],
        "concentration": 7, "ice": [{"stage": "thin_first_year", "floe_size": "small_floe", "concentration": 4},
                                    {"stage": "grey_white", "floe_size": "ice_cake", "concentration": 3}]}


MEDIUM = {**PACK, "concentration": 8, "ice": [{"stage": "thin_first_year", "floe_size": "medium_floe"}]}


def _pack_world(tmp_path_factory, start_north, region=PACK):
    return region_world(tmp_path_factory.getbasetemp() / "pack", 400.0, 600.0, [region], start_north)


@pytest.fixture(scope="module")
def pack(tmp_path_factory):
    """The pack world, and the floes' state after 40 s of steaming into it from its edge."""
    model, data = _pack_world(tmp_path_factory, -80.0)
    step(model, data, 0.1)
    st = data.ice.state
    laid = st.status[:st.n].copy(), st.bonded[:st.n].copy(), broken_counts(data.ice).copy()
    for _ in range(400):
        step(model, data, 0.1)
    return model, data, laid


def _outlines(t):
    g = t.geometry
    return [shapely.Polygon(g.footprint[a:b]) for a, b in zip(g.foot_start[:-1], g.foot_start[1:])]


def test_pack_templates_hold_the_floes_apart_within_the_tile(pack):
    model, _, _ = pack
    loose = [t for t in model.ice.templates if t.floe_field]
    assert len(loose) == 16 and all(t.n_cells > 20 for t in loose)  # the windows of a square of 4 x 4 tiles
    for t in loose:
        floes = _outlines(t)
        area = sum(f.area for f in floes)
        assert shapely.union_all(floes).area == pytest.approx(area, rel=1e-9)  # no two overlap
        assert shapely.box(0, 0, t.side, t.side).contains(shapely.union_all(floes).buffer(-1e-6))
        assert 0.4 < area / t.side**2 < 0.95  # about 7/10 of the tile, leads between
        assert set(np.round(t.thicknesses, 3)) == {0.5, 0.225}  # each type its own thickness
        free = [f for f, loose in zip(floes, t.free_at_start) if loose]
        inner = [f for f in free if shapely.box(0, 0, t.side, t.side).buffer(-1e-6).contains(f)]
        assert len(inner) > 10 and min(np.sqrt(f.area) for f in inner) > 0.5 * MIN_FLOE_SIZE
        assert min(f.area for f in free) >= MIN_FLOE_AREA  # what the tile's edge cuts off a floe: no slivers
        assert np.all(t.thicknesses[t.free_at_start] < 0.3)  # the cakes; the small floes are wider than the beam


def _edge_ice(template, start, end, shift=(0.0, 0.0)):
    """Where the template's floes meet its edge from ``start`` to ``end`` (tile m), moved by
    ``shift`` (m): a line geometry along that edge."""
    edge = shapely.LineString([start, end])
    ice = shapely.union_all(_outlines(template)).buffer(1e-6).intersection(edge)
    return shapely.affinity.translate(ice, *shift)


def test_neighbouring_pack_tiles_continue_each_others_floes(pack):
    """Tile edges do not cut the floes: where a floe reaches over a tile's east or north
    edge, the tile beside it, as the scene lays it, continues the floe from the same stretch
    of that edge. The pack's layout repeats in 4 x 4 tiles, so its fifth and sixth rows
    continue the fourth as the second does the first."""
    model, _, _ = pack
    scene, templates = model.scene, model.ice.templates
    klass = int(scene.tile_class[0])
    assert scene.class_repeat[klass] == 4
    side, ice, missed, pairs = scene.side, 0.0, 0.0, 0
    for tile in range(scene.nx * scene.ny):
        here, turns = tile_layout(scene, tile, klass)
        assert turns == 0
        column, row = tile % scene.nx, tile // scene.nx
        east = tile + 1 if column + 1 < scene.nx else None
        north = tile + scene.nx if row + 1 < scene.ny else None
        for beside, ours, theirs in ((east, ((side, 0), (side, side), (-side, 0)), ((0, 0), (0, side))),
                                     (north, ((0, side), (side, side), (0, -side)), ((0, 0), (side, 0)))):
            if beside is None:
                continue
            mine = _edge_ice(templates[here], *ours)
            next_to = _edge_ice(templates[tile_layout(scene, beside, klass)[0]], *theirs)
            ice, missed, pairs = ice + mine.length, missed + mine.symmetric_difference(next_to).length, pairs + 1
    assert pairs == 38 and ice > 0.3 * pairs * side
    assert missed < 0.05 * ice  # what differs: slivers under MIN_FLOE_AREA the pre-fracture's cuts drop


def test_a_pack_tile_lays_free_floes_that_nothing_broke(pack):
    """The cakes are free floes; the small floes are pre-fractured, intact (or, near the
    bow, already moving as one body each: bonded)."""
    model, data, (status, bonded, counts) = pack
    free = model.ice.starts_free[data.ice.state.gcell[:len(status)]]
    assert free.sum() > 20 and np.all(status[free] == FloeStatus.FREE) and not bonded[free].any()
    held = (status == FloeStatus.INTACT) | ((status == FloeStatus.FREE) & bonded)
    assert (~free).sum() > 100 and np.all(held[~free]) and np.any(status == FloeStatus.INTACT)
    assert counts[BreakCause.HULL] == 0 and counts[BreakCause.CONTACT] == 0


def test_the_hull_pushes_the_floes_aside(pack):
    """Of the cakes laid in the ship's path behind the stem, those within the beam went
    under the hull or aside; those just beside it were pushed outward; the small floes,
    wider than the beam, the hull broke."""
    model, data, _ = pack
    st, ship = data.ice.state, model.ship.particulars
    rows = np.arange(st.n)
    cakes = rows[model.ice.starts_free[st.gcell[rows]]]
    assert data.ship.eta[0] > 30.0 and np.all(st.status[cakes] == FloeStatus.FREE)  # pushed, not broken
    moved = st.xy[cakes] - st.home[cakes]
    off = st.home[cakes, 0] - data.ship.eta[1]
    passed = (st.home[cakes, 1] > 0.0) & (st.home[cakes, 1] < data.ship.eta[0] + 0.5 * ship.length - 10.0)
    path = passed & (np.abs(off) < 0.5 * ship.beam)
    beside = passed & (np.abs(off) >= 0.5 * ship.beam) & (np.abs(off) < 0.5 * ship.beam + 5.0)
    assert path.sum() >= 5 and beside.sum() >= 5
    assert ((np.hypot(*moved[path].T) > 1.0) | st.submerged[cakes][path]).mean() > 0.8
    assert (np.hypot(*moved[beside].T) > 1.0).mean() > 0.6
    assert np.mean(np.sign(off[beside]) * moved[beside, 0]) > 0.5  # outward, m
    assert broken_counts(data.ice)[BreakCause.HULL] > 20


def test_a_medium_floe_splits_along_its_cells_when_rammed(tmp_path_factory, ctx):
    """And the channels draw the field: its 36 templates' cell rasters fit one texture."""
    model, data = _pack_world(tmp_path_factory, -80.0, MEDIUM)
    pieces = [t for t in model.ice.templates if t.floe_field]
    assert all(not t.free_at_start.any() for t in pieces)  # medium floes: pre-fractured, held together
    assert max(t.n_cells for t in pieces) > 500  # the level-ice pre-fracture of 0.5 m, cut to the floes
    for _ in range(400):
        step(model, data, 0.1)
    st = data.ice.state
    assert broken_counts(data.ice)[BreakCause.HULL] > 50
    split = [k for k in range(data.ice.tiles.n) if k not in data.ice.frozen
             and np.any(st.cause[data.ice.tiles.rows(k)] == BreakCause.HULL)]
    held = (st.status == FloeStatus.INTACT) | st.bonded  # the rest of the floes: intact, or moving as one body
    assert split and all(np.any(held[data.ice.tiles.rows(k)]) for k in split)
    far = _channel_classes(model, data, ctx)[60:80, :]  # the tiles not simulated, drawn from their rasters
    assert ctx.error == "GL_NO_ERROR"
    assert (far == CLASS_INDEX["open_water"]).mean() > 0.02 and (far == CLASS_INDEX["level_ice"]).mean() > 0.5


def _channel_classes(model, data, ctx):
    """The class of each pixel of a channel ahead of the ship (180 x 320)."""
    c = ChannelSettings(name="ahead", width=320, height=180, pitch_deg=-10.0, eye=[20.0, 0.0, 25.0])
    view = WorldView()
    view.apply(snapshot(model, data))
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[c])), [c])
    return class_of_pixels(cs.class_images(view)[0])


def test_floes_and_cells_laid_under_the_hull_go_under_it(tmp_path_factory):
    """The ship starts in the pack: the free floes and the small floes' intact cells the
    tiles lay under its hull go under it in the first step. The cells break by no load of
    the bow: no crack patterns about them, no hull breaks counted."""
    model, data = _pack_world(tmp_path_factory, 60.0)  # starts in the pack
    events = step(model, data, 0.1)
    st = data.ice.state
    free = np.nonzero(st.status[:st.n] == FloeStatus.FREE)[0]
    assert st.submerged[free].sum() >= 3
    assert np.hypot(*st.vel[free].T).max() < 1.0  # none thrown out of the hull
    laid_cells = free[~model.ice.starts_free[st.gcell[free]]]  # broken small floes' cells
    assert len(laid_cells) > 20 and np.all(st.cause[laid_cells] == BreakCause.NONE)
    assert st.submerged[laid_cells].mean() > 0.9
    assert broken_counts(data.ice)[BreakCause.HULL] == 0 and len(events.cracked) == 0
    for _ in range(100):  # the bow then breaks and cracks the ice ahead as in any start
        events = step(model, data, 0.1)
    assert broken_counts(data.ice)[BreakCause.HULL] > 0


def test_the_channels_draw_floes_and_the_water_between(pack, ctx):
    model, data, _ = pack
    cls = _channel_classes(model, data, ctx)
    ground = cls[100:, :][cls[100:, :] != CLASS_INDEX["own_ship"]]  # below the horizon, beside the bow
    water, floes = (ground == CLASS_INDEX["open_water"]).mean(), (ground == CLASS_INDEX["broken_floe"]).mean()
    assert water > 0.1 and floes > 0.1  # the tiles simulated: floes, leads between
    far = cls[60:80, :]  # towards the horizon: tiles not simulated, drawn from their templates
    assert (far == CLASS_INDEX["open_water"]).mean() > 0.05 and (far == CLASS_INDEX["level_ice"]).mean() > 0.2


def test_regions_of_one_egg_code_share_a_class_and_its_templates(tmp_path):
    cfg = exercise_config(tmp_path, 400.0, 600.0, 100.0)
    west = {**PACK, "name": "west", "polygon_m": [[0.0, 0.0], [200.0, 0.0], [200.0, 600.0], [0.0, 600.0]]}
    east = {**PACK, "name": "east", "polygon_m": [[200.0, 0.0], [400.0, 0.0], [400.0, 600.0], [200.0, 600.0]]}
    regions = [RegionSettings.model_validate(r) for r in (west, east, {**MEDIUM, "polygon_m": west["polygon_m"][:2]
                                                                       + [[200.0, 100.0], [0.0, 100.0]]})]
    cfg = cfg.model_copy(update={"ice_field": cfg.ice_field.model_copy(update={"regions": regions})})
    laid = field_regions(cfg)
    level_class, level_h = field_tile_classes(cfg, None, laid)
    (tmp_path / "tiles").mkdir()
    packs = lay_floe_fields(cfg, None, laid, level_class, level_h, 24.0, tmp_path / "tiles")
    assert len(packs.templates) == 2 and len(packs.class_h) == len(level_h) + 2  # 7/10 pack, 8/10 medium floes
    assert set(np.unique(packs.tile_class[1:])) == {len(level_h)}  # both halves north of 100 m: one class
    assert set(np.unique(packs.tile_class[0, :2])) == {len(level_h) + 1}  # the medium floes' corner
