"""The pack drifting as a whole (issue 26, item 3): with ``[ice_dynamics] field_drift`` the
whole field (its floes, intact cells, channels, frozen tiles and regions) drifts with the
current and the wind's free drift, in its own frame (``sim_core.ice.drift.IceFrame``). The
pack then drifts over the ship's track and closes it with unbroken floes from upwind; the
floes at rest far from the hull drift with it and stay at rest (no solver work); what the
world publishes carries the frame, so consumers place the ice where it has drifted."""
import dataclasses
import math

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet
from bridge_node.render.classes import class_of_pixels
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.stream.world_view import WorldView
from sim_core.ice.drift import IceFrame, drift_frame
from sim_core.ice.floes import FloeStatus
from sim_core.ice.resting import radii
from sim_core.instructor import SetEnvironment
from sim_core.regimes.settings import RegionSettings
from sim_core.world import Controls, KinematicPose, snapshot, step

DT = 0.1
SPEED = 3.0  # m/s, the ship's passage north through the pack
PASSAGE_S = 80.0
DRIFT_S = 150.0
WIND = 20.0  # m/s from the west: the ice drifts at 0.4 m/s to 120 degrees (Nansen's rule at 74 N)
PACK = {"name": "pack", "polygon_m": [[0.0, 0.0], [400.0, 0.0], [400.0, 600.0], [0.0, 600.0]],
        "concentration": 7, "ice": [{"stage": "thin_first_year", "floe_size": "small_floe", "concentration": 4},
                                    {"stage": "grey_white", "floe_size": "ice_cake", "concentration": 3}]}
STRIP = (15.0, 60.0)  # m north: the part of the track measured, well astern of the held ship


def test_the_frame_relaxes_towards_the_drift_exactly():
    """The frame's velocity relaxes with the drag time, and its offset is the integral of
    that velocity, whatever the step."""
    target, tau = np.array([0.3, -0.1]), 20.0
    one, many = IceFrame(), IceFrame()
    drift_frame(one, target, 60.0, tau)
    for _ in range(600):
        drift_frame(many, target, 0.1, tau)
    assert many.offset == pytest.approx(one.offset, rel=1e-9)
    assert one.velocity == pytest.approx(target * (1.0 - math.exp(-3.0)), rel=1e-12)
    assert one.offset == pytest.approx(target * (60.0 - tau * (1.0 - math.exp(-3.0))), rel=1e-12)


def _intact_share(model, data, track: float, bonded: bool = True) -> float:
    """The share of the measured strip of the ship's track (its beam wide, in the world)
    that unbroken cells cover (intact, or where ``bonded``, bonded to a wide floe moving as a
    whole), from what the world publishes: poses in the ice's frame, and where that frame
    lies."""
    events = snapshot(model, data)
    unbroken = (events.floe_status == FloeStatus.INTACT) | (bonded & data.ice.state.bonded[events.floe_rows])
    rows = events.floe_rows[unbroken]
    xy = events.floe_pose[unbroken, :2] + np.array(events.ice_offset)
    half = 0.5 * model.ship.particulars.beam
    inside = (np.abs(xy[:, 0] - track) < half) & (xy[:, 1] > STRIP[0]) & (xy[:, 1] < STRIP[1])
    area = model.ice.plan_area[data.ice.state.gcell[rows[inside]]].sum()
    return float(area / (2.0 * half * (STRIP[1] - STRIP[0])))


@pytest.fixture(scope="module", params=[True, False], ids=["field_drift", "fast_field"])
def drifted(request, tmp_path_factory):
    """The ship's passage north through 7/10 pack, driven along a line, then held while a
    west wind blows: (model, data, intact share of the track before the wind and after,
    the resting floes and the ice frame's offset at the wind's start, and the rows' places
    then)."""
    cfg = exercise_config(tmp_path_factory.getbasetemp() / "pack", 400.0, 600.0, 100.0, start_north=-80.0)
    field = cfg.ice_field.model_copy(update={"regions": [RegionSettings.model_validate(PACK)]})
    dynamics = cfg.ice_dynamics.model_copy(update={"field_drift": request.param})
    model = build_world(cfg.model_copy(update={"ice_field": field, "ice_dynamics": dynamics}), None)
    data = start_world(model, cfg)
    track, north = float(data.ship.eta[1]), float(data.ship.eta[0])
    for _ in range(round(PASSAGE_S / DT)):
        north += SPEED * DT
        step(model, data, DT, Controls(kinematic=KinematicPose(north, track, 0.0, SPEED)))
    held = Controls(kinematic=KinematicPose(north, track, 0.0, 0.0))
    for _ in range(round(10.0 / DT)):  # the broken floes settle
        step(model, data, DT, held)
    before = _intact_share(model, data, track)
    wind = SetEnvironment((("wind_speed", WIND), ("wind_from", math.radians(270.0))))
    resting = np.flatnonzero(data.ice.state.resting[:data.ice.state.n])
    at_wind = (data.ice_frame.offset.copy(), data.ice.state.xy[resting].copy())
    step(model, data, DT, held, commands=(wind,))
    for _ in range(round(DRIFT_S / DT)):
        step(model, data, DT, held)
    after = _intact_share(model, data, track), _intact_share(model, data, track, bonded=False)
    return model, data, before, after, resting, at_wind


def test_the_drifting_pack_closes_over_the_ship_track(drifted):
    """Right after the passage the track is broken ice; after the drift, unbroken floes from
    upwind cover it again where the field drifts, and where the field is fast the intact
    cells stay (the broken floes drift there, and the wide floes the ship woke, as bodies)."""
    model, data, before, (after, intact), _, _ = drifted
    drifts = model.ice.settings.field_drift
    assert before < 0.05
    if drifts:
        east, north = data.ice_frame.offset
        assert east > 40.0 and north < -15.0  # to about 120 degrees, tens of metres
        assert after > 0.15
    else:
        assert np.all(data.ice_frame.offset == 0.0)
        assert intact < 0.05


def test_resting_floes_drift_with_the_field_and_stay_at_rest(drifted):
    """Floes at rest far from the hull when the wind rose are still at rest in the field's
    frame, all but a few struck by floes the hull woke: they cost no solver step, and the
    world sees them where the field has drifted.
    In a fast field the wind wakes them, to drift through it (``resting.drift_settled``);
    only a floe jammed in the drift (against the level ice) may come to rest again."""
    model, data, _, _, resting, (offset, xy) = drifted
    still = data.ice.state.resting[resting]
    resting_now = data.ice.state.resting[:data.ice.state.n].sum()
    if not model.ice.settings.field_drift:
        assert len(resting) > 30 and still.mean() < 0.5 and resting_now <= 0.05 * len(resting)
        return
    assert resting_now > 100  # more come to rest in the drifting field, as in still water
    # the held hull moves through the drifting field: floes it passes near wake, as ever
    hull = np.array([data.ship.eta[1], data.ship.eta[0]])
    start, end = hull - offset, hull - data.ice_frame.offset  # the hull in the field's frame
    along = np.clip((xy - start) @ (end - start) / ((end - start) @ (end - start)), 0.0, 1.0)
    gap = np.hypot(*(xy - start - along[:, None] * (end - start)).T)
    # beyond the hull's waking radius by a margin: the floes it wakes there strike their
    # neighbours as the pack drifts past the held hull, and those theirs (woken by contact,
    # as ever; in one run such a chain reached 13 m beyond the radius in the drift's 150 s).
    # So a few far floes may be struck, move a little and rest again, as the engine's
    # contact order (by C pointers) differs from process to process: most stay at rest.
    far = gap > radii(model.ice, data.ice)[1] + 20.0
    assert far.sum() >= 10 and still[far].mean() >= 0.8
    moved = np.hypot(*(data.ice.state.xy[resting[far]] - xy[far]).T)
    assert np.mean(moved == 0.0) >= 0.8 and moved[still[far]].max() < 0.5  # in the field's frame
    assert np.hypot(*(data.ice_frame.offset - offset)) > 40.0  # while the field drifted


def test_the_channels_draw_the_ice_where_it_has_drifted(drifted, ctx):
    """The render processes draw in the field's frame: the ship and the ice moved on together
    by the same drift look the same from the bridge; the ship moved alone does not."""
    model, data, *_ = drifted
    c = ChannelSettings(name="ahead", width=320, height=180, pitch_deg=-10.0, eye=[20.0, 0.0, 25.0])
    channels = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[c])), [c])

    def classes(shift: np.ndarray, drifted_too: bool) -> np.ndarray:
        view = WorldView()
        view.apply(snapshot(model, data))
        view.ship = dataclasses.replace(view.ship, north=view.ship.north + shift[1], east=view.ship.east + shift[0])
        if drifted_too:
            view.ice_offset = view.ice_offset + shift
        return class_of_pixels(channels.class_images(view)[0])

    seen, shift = classes(np.zeros(2), False), np.array([30.0, -20.0])
    assert (classes(shift, True) != seen).mean() < 0.002
    assert (classes(shift, False) != seen).mean() > 0.05
