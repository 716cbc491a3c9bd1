"""The sea around floes (EGL offscreen, Mesa llvmpipe): a floe's part above the water is
mirrored in the sea beside it, and a floe the bow has turned under (held a thickness down
and tilted, as the ice model publishes it) shows through the water as a pale blue-green
slab. One floe is moved into open water south of the field, away from every other."""
import dataclasses
import math

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet, create_context
from bridge_node.render.classes import CLASS_INDEX, class_of_pixels
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.stream.world_view import WorldView
from sim_core.ice.floes import FloeStatus
from sim_core.world import snapshot, step

W, H = 192, 108
SHIP = {"north": -400.0, "east": 200.0, "heading": 0.0, "heave": 0.0, "pitch": 0.0, "roll": 0.0}  # in open water south
# of the field, heading north, at rest on the water
LOW = ChannelSettings(name="low", width=W, height=H, hfov_deg=30.0, pitch_deg=-8.0, eye=[85.0, 12.0, 4.0])
SPOT = (212.0, -295.0)  # m (east, north): 20 m ahead of the low eye, 10 m ahead of the bow
REACH = {"lod_distance_m": 1000.0, "reflection_distance_m": 1000.0}  # the floe's tile lies 285 m on, in the field


@pytest.fixture(scope="module")
def exercise(tmp_path_factory):
    """A 400 m x 600 m field of 0.5 m ice, B = 50 m; the ship has steamed 30 s into it: one
    of its free floes."""
    cfg = exercise_config(tmp_path_factory.getbasetemp() / "tiles", 400.0, 600.0, 50.0, start_north=-60.0)
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    for _ in range(300):
        step(model, data, 0.1)
    row = int(np.nonzero(data.ice.state.status == FloeStatus.FREE)[0][0])
    return model, data, row


@pytest.fixture(scope="module")
def ctx():
    return create_context()


def render(ctx, exercise, heave: float | None, roll: float = 0.0, classes: bool = False, **look) -> np.ndarray:
    """The low channel's image (rows, columns, RGB; with ``classes``, its class mask) with the
    floe at SPOT, its centroid `heave` m above the water (None: no floe there) and rolled
    `roll` rad."""
    model, data, row = exercise
    view = WorldView()
    view.apply(snapshot(model, data))
    view.ship = dataclasses.replace(view.ship, **SHIP)
    if heave is not None:
        view.pose[row, :] = SPOT[0], SPOT[1], heave, 0.3, roll, 0.0
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[LOW], **(REACH | look))), [LOW])
    cs.render(view)
    return (cs.class_images(view) if classes else cs.images())[0].astype(float)


def floating(exercise) -> float:
    """The floe's centroid height when it floats level, m."""
    model, data, row = exercise
    return float(model.ice.z_equilibrium[data.ice.state.gcell[row]])


def test_a_floe_is_mirrored_in_the_sea_beside_it(ctx, exercise):
    lift = -0.15  # rad: rolled, its near side 0.4 m out of the water and its top still seen
    mirrored = render(ctx, exercise, floating(exercise), lift)
    plain = render(ctx, exercise, floating(exercise), lift, reflection_distance_m=0.0)
    sea = render(ctx, exercise, None)
    floe = np.abs(plain - sea).sum(axis=-1) > 30  # the floe itself (above and under the water)
    changed = np.abs(mirrored - plain).sum(axis=-1) > 6
    assert changed.sum() >= 15, changed.sum()
    assert (changed & ~floe).sum() >= 5  # also on open water beside the floe
    rows = np.nonzero(changed)[0]
    above = np.nonzero(floe & (plain.mean(axis=-1) > sea.mean(axis=-1) + 60))[0]  # bright snow above water
    assert rows.mean() > above.mean()  # the image lies below the floe on the screen
    far = render(ctx, exercise, floating(exercise), lift, reflection_distance_m=250.0)
    assert np.abs(far - plain).max() == 0  # beyond the reflection distance: none


def test_a_floe_turned_under_shows_through_the_water(ctx, exercise):
    model, data, row = exercise
    under = floating(exercise) - float(model.ice.thickness[data.ice.state.gcell[row]])  # as the ice model holds it
    img = render(ctx, exercise, under, 0.25)
    sea = render(ctx, exercise, None)
    patch = np.abs(img - sea).sum(axis=-1) > 30
    assert patch.sum() >= 40, patch.sum()
    d = (img - sea)[patch].mean(axis=0)  # RGB
    assert d.mean() > 55, d  # well lighter than the sea (a 0.4 m fade, as before, gave 42)
    assert d[1] > d[0] + 20 and d[2] > d[0] + 20, d  # blue-green: the red absorbed first
    r, g, b = img[patch].mean(axis=0)
    assert g > r and b > r, (r, g, b)


def test_the_class_mask_tells_a_floe_turned_under_from_a_floating_one(ctx, exercise):
    model, data, row = exercise
    h = float(model.ice.thickness[data.ice.state.gcell[row]])

    def mask(heave, roll=0.0):
        return class_of_pixels(render(ctx, exercise, heave, roll, classes=True).astype(np.uint8))
    none = mask(None)
    for heave, roll, cls in [(floating(exercise) - h, 0.25, "submerged_floe"), (floating(exercise), 0.0, "broken_floe")]:
        seen = mask(heave, roll)
        floe = seen != none  # the floe's pixels
        assert floe.sum() >= 40, (cls, floe.sum())
        assert np.all(seen[floe] == CLASS_INDEX[cls]), (cls, np.bincount(seen[floe]))


def test_a_floe_turned_over_shows_its_underside_not_its_snow(ctx, exercise):
    """Rolled over (pi) and floating, the floe's bottom faces the sky: where its level
    twin shows snow, it shows the wet, brown-tinged underside."""
    sea = render(ctx, exercise, None)
    counts = {}
    for roll in (0.0, math.pi):
        img = render(ctx, exercise, floating(exercise), roll)
        floe = img[np.abs(img - sea).sum(axis=-1) > 30]
        assert len(floe) >= 40, (roll, len(floe))
        snow = (floe > 170).all(axis=1)
        brown = (floe[:, 0] > floe[:, 2] + 5) & (floe[:, 1] > floe[:, 2] + 5)  # red and green over blue
        counts[roll] = snow.sum(), brown.sum()
    assert counts[0.0][0] >= 20 and counts[0.0][1] == 0, counts
    assert counts[math.pi][0] == 0 and counts[math.pi][1] >= 20, counts
