"""Bending cracks (issue 28, item 1): where the hull loads the level ice, radial and
circumferential cracks run out into it (``sim_core.ice.bending``), the cracked cells stay in
the sheet until they break free, the state stream carries the cracks to late joiners, and
the environment pass draws them as thin dark lines that later bound the floes."""
import dataclasses
import math

import numpy as np
import pytest
from scipy import ndimage
from test_render import channel, view_of
from test_render_frozen import channel_over

from bridge_node.render.channels import ChannelSet
from bridge_node.render.classes import CLASS_INDEX, class_of_pixels
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import RenderSettings
from bridge_node.stream.codec import decode, encode
from bridge_node.stream.world_view import WorldView
from sim_core.ice.bending import (PIECE, RADIAL_REACH, breaking_length, crack_labels, crack_lines,
                                  outward)
from sim_core.ice.floes import FloeStatus
from sim_core.ice.tiles import freeze_tile, thaw_tile
from sim_core.scene.switches import frozen_cracks_of, frozen_floes_of
from sim_core.material import characteristic_length
from sim_core.world import snapshot, step


def test_the_breaking_length_is_the_papers_table_3():
    assert breaking_length(0.5) == pytest.approx(3.3, abs=1e-9)
    assert breaking_length(1.0) == pytest.approx(4.5, abs=1e-9)
    assert breaking_length(0.2) < breaking_length(0.5) < breaking_length(1.5)


def _grid(spacing=1.0, half=30.0):
    x, y = np.meshgrid(np.arange(-half, half + 1e-9, spacing), np.arange(-half, half + 1e-9, spacing))
    return np.column_stack([x.ravel(), y.ravel()])


@pytest.mark.parametrize("wedges", [3, 4, 5])
def test_pieces_lie_ahead_within_the_breaking_length_split_into_wedges(wedges):
    offset = _grid()
    lb, reach = 4.0, 17.0
    labels = crack_labels(offset, np.ones(len(offset)), wedges, 0.0, 11, lb, reach)
    dist = np.hypot(*offset.T)
    piece = (labels & PIECE) != 0
    assert piece.any()
    assert (dist[piece] <= lb).all() and (offset[piece, 0] >= 0).all()  # ahead, into the ice only
    assert len(np.unique(labels[piece])) == wedges
    assert not labels[offset[:, 0] < -1.0].any()  # nothing behind the load (the hull's side)


def test_radial_cracks_run_from_the_pieces_to_their_reach():
    offset = _grid(0.5)
    lb, reach = 4.0, 17.0
    labels = crack_labels(offset, np.full(len(offset), 1.0), 4, 0.0, 3, lb, reach)
    radial = (labels != 0) & ((labels & PIECE) == 0)
    dist = np.hypot(*offset.T)
    assert radial.any() and dist[radial].max() > 0.9 * reach
    assert dist[radial].max() <= reach + 1.0 and dist[radial].min() > lb
    # three radial cracks between four wedges, each with its two sides labelled apart
    assert len(np.unique(labels[radial])) == 6
    # a crack is a line: the cells on it are a thin share of the disc it spans
    assert radial.sum() < 0.2 * ((dist <= reach) & (offset[:, 0] > 0)).sum()


def test_a_crack_runs_between_different_labels_with_a_piece_or_both_cracked():
    p, q, a, b = PIECE | 1, PIECE | 2, 5, 6
    assert crack_lines([p, p, p, a, a, 0, 0], [q, 0, a, b, 0, 0, p]).tolist() == \
        [True, True, True, True, False, False, True]
    assert not crack_lines([p], [p])[0]  # within one wedge: its cells hold together


def test_the_outward_direction_fans_out_round_the_stem():
    at = dict(hull_xy=np.zeros(2), angle=0.0, stern=-75.0, stem=75.0, half_beam=12.0)
    assert outward(np.array([80.0, 0.0]), **at) == pytest.approx([1.0, 0.0])
    assert outward(np.array([0.0, 20.0]), **at) == pytest.approx([0.0, 1.0])
    bow_shoulder = outward(np.array([70.0, 10.0]), **at)
    assert 0.2 < bow_shoulder[0] < 0.9 and bow_shoulder[1] > 0.4


@pytest.fixture(scope="module")
def cracked(exercise):
    """The render tests' world (0.5 m ice, 70 s in), its cracked intact cells and the ship's
    stem and heading (world x east, y north)."""
    model, data = exercise
    st = data.ice.state
    rows = np.flatnonzero((st.crack[:st.n] != 0) & (st.status[:st.n] == FloeStatus.INTACT))
    s = data.ship
    heading = np.array([math.sin(s.eta[5]), math.cos(s.eta[5])])
    stem = np.array([s.eta[1], s.eta[0]]) + heading * model.ship.particulars.length / 2
    return model, data, rows, stem, heading


def test_the_hull_cracks_the_level_ice_ahead_of_the_stem_within_the_bending_reach(cracked):
    model, data, rows, stem, heading = cracked
    st = data.ice.state
    reach = RADIAL_REACH * characteristic_length(0.5, model.ice.material)
    d = st.home[rows] - stem
    ahead = d @ heading
    assert len(rows) > 50
    assert (ahead > 1.0).sum() >= 5  # cracks run out ahead of the stem
    assert ahead.max() < reach + 5.0  # but no farther than the sheet bends


def test_cracked_cells_break_free_later_along_their_cracks(cracked):
    model, data, rows, _, _ = cracked
    st = data.ice.state
    labels = st.crack[rows].copy()
    for _ in range(100):  # 10 s more: the bow reaches the cracks ahead of it
        step(model, data, 0.1)
    free = st.status[rows] == FloeStatus.FREE
    assert free.any()  # cracked cells separated, as floes bounded by their cracks
    assert (st.crack[rows[free]] == labels[free]).all()  # a floe keeps the label it cracked with


def test_the_stream_carries_the_cracks_to_a_late_joiner(exercise):
    model, data = exercise
    events = snapshot(model, data)
    assert len(events.cracked) > 0
    decoded, _, _ = decode(encode(events))
    assert np.array_equal(decoded.cracked, events.cracked)
    view = WorldView()
    view.apply(decoded)
    rows = events.cracked["row"].astype(np.int64)
    assert np.array_equal(view.crack[rows], events.cracked["label"])
    again = view.to_snapshot().cracked  # the view's own snapshot, for its late joiners (rows in its order)
    assert np.array_equal(np.sort(again, order="row"), np.sort(events.cracked, order="row"))


def _crack_mask(ctx, model, view):
    astern = channel(yaw_deg=180.0, pitch_deg=-35.0, eye=[-100.0, 0.0, 30.0])  # above the wake, looking down it
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[astern])), [astern])
    cs.render(view)
    cls = class_of_pixels(cs.class_images(view)[0])
    return cls == CLASS_INDEX["crack"], cls == CLASS_INDEX["level_ice"]


def test_cracks_are_thin_dark_lines_in_the_class_mask(ctx, exercise):
    model, data = exercise
    crack, ice = _crack_mask(ctx, model, view_of(model, data))
    assert crack.sum() > 20, np.bincount(ice.ravel())
    assert crack.sum() < 0.5 * ice.sum()
    # lines, not patches: eroding by one pixel leaves almost none of them
    assert ndimage.binary_erosion(crack).sum() < 0.1 * crack.sum()
    view = view_of(model, data)
    view.crack[:] = 0  # the same moment with no cracks published: none drawn
    crack, _ = _crack_mask(ctx, model, view)
    assert not crack.any()


def _cracks_over(ctx, model, view, c) -> np.ndarray:
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[c])), [c])
    cs.render(view)
    return class_of_pixels(cs.class_images(view)[0]) == CLASS_INDEX["crack"]


def test_a_frozen_tiles_cracks_are_drawn_where_they_were(ctx, exercise):
    model, data = exercise  # (this test and the next change the world: they run last)
    st, tiles = data.ice.state, data.ice.tiles
    live = [k for k in range(tiles.n) if tiles.row_count[k] > 0]
    k = max(live, key=lambda p: np.count_nonzero(st.crack[tiles.rows(p)][st.status[tiles.rows(p)] == 0]))
    before = view_of(model, data)
    c = channel_over(before, k, model)
    live_cracks = _cracks_over(ctx, model, before, c)
    frozen = sorted({*before.frozen, k})
    freeze_tile(data.ice, k)

    def frozen_view() -> WorldView:
        view = view_of(model, data)
        view.apply(dataclasses.replace(snapshot(model, data), frozen=np.array(frozen),
                                       frozen_floes=frozen_floes_of(data.ice, frozen),
                                       frozen_cracks=frozen_cracks_of(data.ice, frozen)))
        return view

    after = frozen_view()
    assert k in after.frozen and len(after.frozen_cracks[k]) > 10
    frozen_cracks = _cracks_over(ctx, model, after, c)
    assert live_cracks.sum() > 20
    assert (live_cracks & frozen_cracks).sum() > 0.9 * live_cracks.sum()  # the same lines, from the frozen entries
    # a record naming a cell the tile lacks (which the stream's bounds let through) is dropped
    bad = frozen_view()
    record = bad.frozen_cracks[k][:1].copy()
    record["cell"] = 10 ** 6
    bad.frozen_cracks[k] = np.concatenate([bad.frozen_cracks[k], record])
    assert np.array_equal(_cracks_over(ctx, model, bad, c), frozen_cracks)


def test_a_tiles_cracks_survive_its_freeze_and_thaw(exercise):
    model, data = exercise  # (this test changes the world: it runs last)
    st, tiles = data.ice.state, data.ice.tiles
    live = [k for k in range(tiles.n) if tiles.row_count[k] > 0]
    k = max(live, key=lambda p: np.count_nonzero(st.crack[tiles.rows(p)][st.status[tiles.rows(p)] == 0]))
    rows = tiles.rows(k)
    intact = st.status[rows] == FloeStatus.INTACT
    cells = np.flatnonzero(intact & (st.crack[rows] != 0))
    labels = st.crack[rows][cells].copy()
    assert len(cells) > 10
    freeze_tile(data.ice, k)
    kept = data.ice.frozen.cracks(k)
    assert np.array_equal(np.sort(kept["cell"]), cells) and (kept["placement"] == k).all()
    # as the world publishes a tile frozen in a step: its cracks travel to the view
    events = dataclasses.replace(snapshot(model, data), frozen=np.array([k]),
                                 frozen_cracks=frozen_cracks_of(data.ice, [k]))
    view = WorldView()
    view.apply(decode(encode(events))[0])
    assert np.array_equal(np.sort(view.frozen_cracks[k]["cell"]), cells)
    assert np.array_equal(np.sort(view.to_snapshot().frozen_cracks["cell"]), cells)  # and on to its late joiners
    thaw_tile(model.ice, data.ice, k)
    rows = tiles.rows(k)
    assert np.array_equal(st.crack[rows][cells], labels)  # the thawed rows cracked as they froze
    assert k not in data.ice.frozen


def _crack_ahead_reference(model, st, tiles, loaded, hull_xy, angle, outline):
    """``crack_ahead`` as first written: for each load, every row of the live tiles whose box
    is within its reach (the reference the faster gathering must agree with)."""
    from sim_core.ice.bending import _pattern, breaking_length
    stern, stem = float(outline[:, 0].min()), float(outline[:, 0].max())
    half_beam = float(np.abs(outline[:, 1]).max())
    sides = np.array([t.side for t in model.templates])
    cracked = []
    for r in loaded.tolist():
        if st.crack[r] != 0:
            continue
        h = float(model.thickness[st.gcell[r]])
        reach = RADIAL_REACH * characteristic_length(h, model.material)
        point = st.home[r].astype(float)
        live = np.flatnonzero(tiles.row_count > 0)
        lo = tiles.corner[live]
        gap = np.maximum(np.maximum(lo - point, point - (lo + sides[tiles.template[live]][:, None])), 0.0)
        rows = np.concatenate([np.zeros(0, np.int64)] + [tiles.rows(k) for k in live[np.hypot(*gap.T) <= reach]])
        rows = rows[(st.status[rows] == FloeStatus.INTACT) & (st.crack[rows] == 0)]
        if not len(rows):
            continue
        n = outward(point, hull_xy, angle, stern, stem, half_beam)
        d = st.home[rows].astype(float) - point
        offset = np.column_stack([d @ n, d @ np.array([-n[1], n[0]])])
        wedges, turn, base = _pattern(r)
        labels = crack_labels(offset, np.sqrt(model.plan_area[st.gcell[rows]]), wedges, turn, base,
                              float(breaking_length(h)), reach)
        st.crack[rows[labels != 0]] = labels[labels != 0]
        cracked.append(rows[labels != 0])
    return np.unique(np.concatenate([np.zeros(0, np.int64), *cracked]))


def test_many_fresh_loads_in_one_step_crack_as_one_load_at_a_time_did(exercise):
    from sim_core.ice.bending import crack_ahead
    model, data = exercise
    st, tiles = data.ice.state, data.ice.tiles
    s = data.ship
    hull_xy, angle = np.array([s.eta[1], s.eta[0]]), math.pi / 2 - s.eta[5]
    outline = data.ice.contacts.hulls[0].outline
    fresh = np.flatnonzero((st.status[:st.n] == FloeStatus.INTACT) & (st.crack[:st.n] == 0))
    stem = hull_xy + model.ship.particulars.length / 2 * np.array([math.cos(angle), math.sin(angle)])
    loaded = fresh[np.argsort(np.hypot(*(st.home[fresh] - stem).T))[:60]]  # a turn: many fresh loads at once
    before = st.crack.copy()
    got = crack_ahead(model.ice, st, tiles, loaded, hull_xy, angle, outline)
    labels = st.crack.copy()
    st.crack[:] = before
    want = _crack_ahead_reference(model.ice, st, tiles, loaded, hull_xy, angle, outline)
    try:
        assert len(want) > 100 and np.array_equal(got, want) and np.array_equal(labels, st.crack)
    finally:
        st.crack[:] = before
