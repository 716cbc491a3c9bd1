"""What the instructor station's tests share: the map's colours (``MAP_COLORS`` in
map.js), the exercise's config, and looking at the map in the browser (screenshots, where
a world point is drawn, holding the view still)."""
from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
from PIL import Image

from bridge_node.common.network import free_port
from bridge_node.station.harness import wait_until
from bridge_node.station.wire import unpack

SHIP_RGB = (232, 51, 31)  # MAP_COLORS.ship in map.js
FLOE_RGB = (247, 251, 254)  # MAP_COLORS.floe
LEVEL_ICE_RGB = (210, 221, 230)  # MAP_COLORS.ice
WATER_RGB = (23, 54, 79)  # MAP_COLORS.water
REGION_RGB = (255, 122, 217)  # MAP_COLORS.region
RIDGE_RGB = (224, 64, 192)  # MAP_COLORS.ridge
BRASH_RGB = (133, 150, 166)  # MAP_COLORS.brash
CONVOY_RGB = (255, 210, 63)  # MAP_COLORS.convoy


def write_config(folder: Path, stream: tuple[int, int], control: int, port: int, extra: str = "") -> Path:
    """An 800 m field of 0.3 m ice with an ice-free corner (a lake), the ship's bow in it,
    loopback ports of its own, and NMEA 0183 instrument sentences on UDP (the session
    record's tx sentences a debrief plays)."""
    text = ('[ship]\nname = "polar_cargo"\n[ice_field]\nwidth = 800.0\nheight = 800.0\nthickness = 0.3\n'
            '[[ice_field.regions]]\nname = "lake"\nconcentration = 0\n'  # open water in the north-west corner
            'polygon_m = [[0.0, 600.0], [200.0, 600.0], [200.0, 800.0], [0.0, 800.0]]\n'
            '[[ice_field.regions]]\nname = "brash"\nconcentration = 9\n'  # brash alone in the south-east
            'ice = [{ stage = "grey_white", floe_size = "brash" }]\n'
            'polygon_m = [[600.0, 0.0], [800.0, 0.0], [800.0, 200.0], [600.0, 200.0]]\n'
            '[[ice_field.ridges]]\nname = "ridges"\ndirection_deg = 90.0\nspacing_m = 150.0\n'  # one ridge line,
            'through_m = [0.0, 400.0]\npolygon_m = [[550.0, 350.0], [800.0, 350.0], [800.0, 450.0], [550.0, 450.0]]\n'
            '[exercise]\nstart_north = -20.0\nstart_east = 450.0\n'
            f'[paths]\ncache_dir = "{folder / "tiles"}"\nsession_dir = "{folder / "sessions"}"\n'
            f'[stream]\npublish = "tcp://127.0.0.1:{stream[0]}"\nsnapshot = "tcp://127.0.0.1:{stream[1]}"\n'
            f'[control]\nendpoint = "tcp://127.0.0.1:{control}"\n' + extra +
            f'[instructor]\nport = {port}\n' + ("allow_network = true\n" if "token" in extra else "") +
            f'[[links]]\nname = "instruments"\ntype = "nmea0183"\nudp_port = {free_port()}\n')
    path = folder / f"exercise-{port}.toml"
    path.write_text(text)
    return path


def screenshot(browser) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(browser.get_screenshot_as_png())).convert("RGB")).astype(int)


def near(image: np.ndarray, rgb: tuple[int, int, int], tolerance: int = 12) -> np.ndarray:
    return (np.abs(image - np.array(rgb)) <= tolerance).all(axis=2)


def canvas_pixel(browser, east: float, north: float) -> tuple[float, float]:
    """Where a world point is drawn, in page pixels (the map's own transform)."""
    return browser.execute_script(
        "const r = map.canvas.getBoundingClientRect(), w = r.width, h = r.height;"
        "return [r.left + w / 2 + (arguments[0] - map.cx) * map.scale, r.top + h / 2 - (arguments[1] - map.cy) * map.scale];",
        east, north)


def view(browser, east: float, north: float, scale: float) -> None:
    """Hold the map still on a world point at a scale (px/m), and wait for it to be drawn."""
    browser.execute_script("map.setFollow(false); map.cx = arguments[0]; map.cy = arguments[1]; map.scale = arguments[2];"
                           "map.dirty = true;", east, north, scale)
    draws = browser.execute_script("return window.stationStats.draws")
    wait_until(lambda: browser.execute_script("return window.stationStats.draws") > draws + 1, 10, "a redraw")


def shown_time(browser) -> float:
    return float(browser.find_element("id", "sim-time").text.split()[0])


def endpoint_of(config: Path) -> str:
    """The control endpoint a station test's config names."""
    return next(line.split('"')[1] for line in config.read_text().splitlines() if line.startswith("endpoint"))


def websocket_refused(port: int) -> None:
    """A WebSocket to the station without the token is refused (or closed unanswered)."""
    from websockets.exceptions import ConnectionClosed, InvalidStatus
    from websockets.sync.client import connect

    try:
        with connect(f"ws://127.0.0.1:{port}/ws", open_timeout=10) as ws:
            ws.recv(timeout=5)
    except InvalidStatus as exc:
        assert exc.response.status_code in (401, 403)
    except ConnectionClosed:
        pass
    else:
        raise AssertionError("a WebSocket without the token got a message")


def websocket_hello(port: int, token: str) -> dict:
    """With the token: the hello message, after which the geometry comes."""
    from websockets.sync.client import connect

    with connect(f"ws://127.0.0.1:{port}/ws?token={token}", open_timeout=10, max_size=None) as ws:
        hello = json.loads(ws.recv(timeout=10))
        header, arrays = unpack(ws.recv(timeout=10))
        assert header["type"] == "geometry" and len(arrays["outline_start"]) > 1
        return hello
