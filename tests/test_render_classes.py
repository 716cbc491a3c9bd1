"""The class mask (issue 28, item 5): each channel drawn from the same camera with each
pixel coloured by what it shows. It agrees with the shaded picture (sky where the picture
shows sky, level ice where it shows bright snow, water and floes in the broken channel
astern), names the own ship and other vessels apart, and ``icebridge render-snapshot
--classes`` writes it beside each channel's PNG with a legend."""
import math

import numpy as np
from conftest import run_cli
from PIL import Image
from test_render import H, W, channel, is_ice, is_sky, view_of

from bridge_node.links.traffic_picture import TRAFFIC_DTYPE
from bridge_node.render.channels import ChannelSet
from bridge_node.render.classes import CLASS_INDEX, CLASSES, class_of_pixels, class_shares
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import RenderSettings


def _both(ctx, model, view, c):
    """The shaded image and the class indices of one channel."""
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[c])), [c])
    cs.render(view)
    return cs.images()[0], class_of_pixels(cs.class_images(view)[0])


def test_every_pixel_holds_exactly_one_class_colour(ctx, exercise):
    model, data = exercise
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=[channel()])), [channel()])
    view = view_of(model, data)
    mask, = cs.class_images(view)
    palette = {c for _, c in CLASSES}
    assert {tuple(int(v) for v in px) for px in mask.reshape(-1, 3)} <= palette


def test_ahead_the_mask_agrees_with_the_picture(ctx, exercise):
    model, data = exercise
    img, cls = _both(ctx, model, view_of(model, data), channel(pitch_deg=-8.0, eye=[80.0, 0.0, 20.0]))
    sky, ice = cls == CLASS_INDEX["sky"], cls == CLASS_INDEX["level_ice"]
    assert sky.mean() > 0.05 and ice.mean() > 0.3
    assert is_sky(img[sky]).mean() > 0.95  # where the mask says sky, the picture shows sky
    assert is_ice(img[ice]).mean() > 0.9  # and bright level ice where it says level ice
    assert not is_ice(img[cls == CLASS_INDEX["open_water"]]).any()


def test_astern_the_broken_channel_is_water_and_floes(ctx, exercise):
    model, data = exercise
    astern = channel(yaw_deg=180.0, pitch_deg=-35.0, eye=[-100.0, 0.0, 30.0])  # above the wake, looking down it
    img, cls = _both(ctx, model, view_of(model, data), astern)
    centre = cls[H // 2:, W // 3: 2 * W // 3]  # down the channel
    shares = np.bincount(centre.ravel(), minlength=len(CLASSES)) / centre.size
    assert shares[CLASS_INDEX["broken_floe"]] > 0.5 and shares[CLASS_INDEX["open_water"]] > 0.01, shares
    sides = np.hstack([cls[H // 2:, : W // 8], cls[H // 2:, -W // 8:]])
    assert (sides == CLASS_INDEX["level_ice"]).mean() > 0.5  # the unbroken ice beside the channel
    floe, water = cls == CLASS_INDEX["broken_floe"], cls == CLASS_INDEX["open_water"]
    assert img[floe].mean() > img[water].mean() + 40  # floes are the bright parts of the channel


def test_own_ship_and_other_vessels_are_told_apart(ctx, exercise):
    model, data = exercise
    view = view_of(model, data)
    s = view.ship
    az = s.heading + math.radians(5.0)
    view.traffic = np.array([(7, s.east + 400 * math.sin(az), s.north + 400 * math.cos(az), 1.0, 5.0, 120.0, 20.0)],
                            dtype=TRAFFIC_DTYPE)
    _, cls = _both(ctx, model, view, channel(pitch_deg=-8.0))  # from the bridge: the forecastle below
    own, other = cls == CLASS_INDEX["own_ship"], cls == CLASS_INDEX["other_vessel"]
    assert own[H // 2:].mean() > 0.05  # the forecastle fills the lower picture
    assert other.sum() > 5
    columns = np.nonzero(other)[1]
    assert columns.mean() > W / 2  # 5 deg to starboard of the bow
    assert np.nonzero(other)[0].max() < H // 2 + 10  # on the sea, near the horizon


def test_render_snapshot_writes_the_masks_and_a_legend(tmp_path):
    done = run_cli("render-snapshot", "--time", "20", "--classes", "--out", str(tmp_path))
    assert done.returncode == 0, done.stderr
    masks = sorted(tmp_path.glob("snapshot_*_classes.png"))
    frames = [p for p in tmp_path.glob("snapshot_*.png") if not p.stem.endswith("_classes")]
    assert len(masks) == len(frames) >= 1
    assert (tmp_path / "classes_legend.png").is_file()
    for mask in masks:
        frame = mask.with_name(mask.name.replace("_classes", ""))
        with Image.open(mask) as m, Image.open(frame) as f:
            assert m.size == f.size
            shares = class_shares(np.asarray(m.convert("RGB")))
        assert shares["sky"] > 0.01 and shares["level_ice"] + shares["open_water"] > 0.1, (mask.name, shares)
