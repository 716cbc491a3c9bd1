"""A fog change from the instructor station changes a render process's picture (issue 25):
``icebridge run`` with a render process that writes its channel every half simulated
second (``--frames-every``), ``icebridge instructor`` on it, and the station's page in
headless Chromium, each in its own process on loopback. The page's "clear 8 km" and then
"fog 200 m" buttons set the visibility; the pictures the render process drew after each, in
the same run, are compared where fog acts: far from the eye, the contrast of the ice and
the water beyond it falls, and their colour goes to the fog's, the sky's at the horizon."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from conftest import exercise_toml
from PIL import Image

from bridge_node.common.network import free_port
from bridge_node.station.harness import (
    chromium,
    ctl_status,
    node_and_station,
    open_page,
    require_chromium,
    wait_until,
)

require_chromium()  # a failure, not a skip
W, H, PITCH_DEG, EYE_M = 320, 180, -6.0, 25.0
# to starboard (east, away from the late-morning sun in the south), from 30 m off the hull (none of the ship in
# view): the field's 0.3 m ice on the left, the open water south of it on the right, to the horizon
CHANNEL = (f'[[render.channels]]\nname = "starboard"\nyaw_deg = 90.0\npitch_deg = {PITCH_DEG}\nwidth = {W}\n'
           f'height = {H}\neye = [10.0, 30.0, {EYE_M}]\n')


def row_at(depression_deg: float) -> int:
    """The pixel row of a ray that far below the horizon (a level ship)."""
    vfov = 2.0 * math.atan(math.tan(math.radians(30.0)) * H / W)  # the channel's 60 deg across
    return round((1.0 - math.tan(math.radians(-depression_deg - PITCH_DEG)) / math.tan(vfov / 2.0)) / 2.0 * H - 0.5)


def picture_after(out: Path, sim_time: float) -> np.ndarray:
    """The first picture the render process wrote a simulated second or more after
    ``sim_time``, once a later one is there (so that it is written whole)."""
    def written() -> Path | None:
        later = sorted((float(p.name[1:9]), p) for p in (out / "frames").glob("t*_starboard.png")
                       if float(p.name[1:9]) >= sim_time + 1.0)
        return later[0][1] if len(later) > 1 else None
    return np.asarray(Image.open(wait_until(written, 60, f"a picture after {sim_time:.1f} s")).convert("RGB"), float)


def visibility_from_the_page(browser, config: Path, metres: int) -> float:
    """Click the page's visibility button; the node's simulated time once it has the visibility."""
    browser.find_element("css selector", f"[data-visibility='{metres}']").click()
    return wait_until(lambda: (s := ctl_status(config))["visibility_m"] == metres and s, 20,
                      f"the node's visibility at {metres} m")["time_s"]


def test_a_fog_change_from_the_page_changes_the_render_process_picture(tmp_path):
    control, port = f"tcp://127.0.0.1:{free_port()}", free_port()
    config = exercise_toml(tmp_path, CHANNEL, control=f'endpoint = "{control}"', instructor=f"port = {port}")
    url, out = f"http://127.0.0.1:{port}/", tmp_path / "out"
    with node_and_station(tmp_path, config, control, url, "--render", "local", "--frames-every", "0.5", "--duration",
                          "600", "--out", str(out)), chromium() as browser:
        open_page(browser, url)
        clear = picture_after(out, visibility_from_the_page(browser, config, 8000))
        fog = picture_after(out, visibility_from_the_page(browser, config, 200))
    for name, image in (("clear", clear), ("fog", fog)):
        Image.fromarray(image.astype(np.uint8)).save(tmp_path / f"{name}.png")
    horizon = row_at(0.0)
    far = slice(horizon + 2, row_at(math.degrees(math.atan2(EYE_M, 150.0))))  # 150 m off and beyond, below the sky
    luminance = np.array([0.2126, 0.7152, 0.0722])
    contrast = {name: (image[far] @ luminance).std() for name, image in (("clear", clear), ("fog", fog))}
    assert contrast["clear"] > 8.0, f"no contrast far off in clear weather: {contrast}"
    assert contrast["fog"] < 0.25 * contrast["clear"], f"the far field's contrast in fog: {contrast}"
    to_fog = {name: np.linalg.norm(image[far].mean(axis=(0, 1)) - image[horizon - 3:horizon].mean(axis=(0, 1)))
              for name, image in (("clear", clear), ("fog", fog))}  # the far field's colour from the sky's at the horizon
    assert to_fog["fog"] < 0.5 * to_fog["clear"] and to_fog["fog"] < 12.0, f"far field to the fog's colour: {to_fog}"
