"""The instructor station (issue 25, item 5), as an instructor uses it: ``icebridge run`` and
``icebridge instructor`` in their own processes on loopback, the page opened in headless
Chromium (Debian's, driven by Selenium). The map is checked on the pixels of screenshots;
the page's commands are checked in the node's status (``icebridge ctl status``). One node
and one station serve the tests in order; the map's test comes first and waits for the ship
to break a channel behind it."""
from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from bridge_node.control.client import request
from bridge_node.control.save_point import read_save
from bridge_node.common.network import free_port
from bridge_node.station.harness import (
    chromium,
    ctl_status,
    http,
    node_and_station,
    open_page,
    require_chromium,
    start,
    stop,
    wait_until,
)
from station_helpers import (
    SHIP_RGB,
    FLOE_RGB,
    LEVEL_ICE_RGB,
    WATER_RGB,
    REGION_RGB,
    RIDGE_RGB,
    BRASH_RGB,
    CONVOY_RGB,
    write_config,
    screenshot,
    near,
    canvas_pixel,
    view,
    shown_time,
    endpoint_of,
    websocket_hello,
    websocket_refused,
)

REPO = Path(__file__).resolve().parent.parent
require_chromium()  # a failure, not a skip: the browser checks must run wherever the suite does
TOKEN = "instructor-test-token-0123456789"
@pytest.fixture(scope="module")
def exercise(tmp_path_factory):
    """A running node and a station on it: (config, station URL, folder)."""
    folder = tmp_path_factory.mktemp("station")
    stream, control, port = (free_port(), free_port()), free_port(), free_port()
    config = write_config(folder, stream, control, port)
    url = f"http://127.0.0.1:{port}/"
    with node_and_station(folder, config, f"tcp://127.0.0.1:{control}", url, "--render", "none", "--duration", "600",
                          "--json", "--out", str(folder / "out")):
        yield config, url, folder


@pytest.fixture(scope="module")
def browser():
    with chromium() as driver:
        yield driver


def test_map_shows_ship_and_floes(exercise, browser):
    config, url, folder = exercise
    open_page(browser, url, floes=100)
    wait_until(lambda: browser.execute_script("return lastFrame.ship.north") > 120.0, 120,
               "the ship's stern 45 m into the ice (a channel behind it)")
    request(endpoint_of(config), {"command": {"command": "freeze"}}, None)  # a still picture to compare with
    try:
        status = wait_until(lambda: (s := ctl_status(config))["frozen"] and s, 20, "the node frozen")
        wait_until(lambda: browser.execute_script("return lastFrame.environment.frozen"), 10, "the page frozen")
        east, north, heading = status["east_m"], status["north_m"], math.radians(status["heading_deg"])
        view(browser, east, north, 2.0)
        image = screenshot(browser)
        Image.fromarray(image.astype(np.uint8)).save(folder / "map.png")

        def box(forward: float, starboard: float, half: int) -> np.ndarray:
            """The screenshot around a point of the ship's frame (m), +-half px."""
            x, y = (round(v) for v in canvas_pixel(
                browser, east + forward * math.sin(heading) + starboard * math.cos(heading),
                north + forward * math.cos(heading) - starboard * math.sin(heading)))
            return image[y - half:y + half + 1, x - half:x + half + 1]

        ship = near(box(0.0, 0.0, 15), SHIP_RGB, 20).mean()
        assert ship > 0.5, f"the own ship's colour covers {ship:.0%} around its place"
        assert not near(box(0.0, 60.0, 15), SHIP_RGB, 20).any(), "ship colour 60 m abeam"
        floes = near(box(0.0, 0.0, 200), FLOE_RGB, 6).sum()  # broken floes beside and ahead of the hull
        assert floes > 2000, f"floe pixels {floes}"
        channel = near(box(-100.0, 0.0, 20), LEVEL_ICE_RGB, 6).mean()  # 25 m astern of the stern: broken
        level = near(box(-100.0, 60.0, 20), LEVEL_ICE_RGB, 6).mean()  # 60 m to starboard of it: intact
        assert channel < 0.5 < level, f"level ice: {channel:.0%} of the channel astern, {level:.0%} beside it"
    finally:
        request(endpoint_of(config), {"command": {"command": "resume"}}, None)


def test_the_map_shows_the_regions_and_their_open_water(exercise, browser):
    view(browser, 200.0, 600.0, 1.0)
    image = screenshot(browser)

    def around(east: float, north: float) -> np.ndarray:
        x, y = (round(v) for v in canvas_pixel(browser, east, north))
        return image[y - 10:y + 11, x - 10:x + 11]
    assert near(around(100.0, 660.0), WATER_RGB, 6).mean() > 0.9  # the lake
    assert near(around(300.0, 700.0), LEVEL_ICE_RGB, 6).mean() > 0.9  # the field's ice beside it
    assert near(around(100.0, 500.0), LEVEL_ICE_RGB, 6).mean() > 0.9
    edge = [near(around(200.0, north), REGION_RGB, 40).any() for north in (620.0, 650.0, 680.0, 710.0, 740.0)]
    assert np.mean(edge) >= 0.6, edge  # its outline, dashed, on its east edge
    assert not near(around(300.0, 700.0), REGION_RGB, 40).any()
    view(browser, 650.0, 400.0, 1.0)
    image = screenshot(browser)
    assert all(near(around(east, 400.0), RIDGE_RGB, 30).any() for east in (600.0, 650.0, 700.0, 750.0))
    assert not near(around(650.0, 370.0), RIDGE_RGB, 30).any()  # the ridge's line, east-west at 400 m
    view(browser, 650.0, 150.0, 1.0)
    image = screenshot(browser)
    assert near(around(640.0, 30.0), BRASH_RGB, 6).mean() > 0.9  # brash alone: not open water (its label mid-way)
    assert near(around(550.0, 150.0), LEVEL_ICE_RGB, 6).mean() > 0.9  # the level ice beside it
    # a field that has drifted 150 m east: its ice, the lake and the outlines are drawn there
    browser.execute_script("window.applyFrame = map.applyFrame;"
                           "map.applyFrame = (h, a) => window.applyFrame.call(map, {...h, ice_offset: [150, 0]}, a);")
    try:
        view(browser, 200.0, 600.0, 1.0)
        image = screenshot(browser)
        assert near(around(250.0, 660.0), WATER_RGB, 6).mean() > 0.9  # the lake, moved on
        assert near(around(450.0, 700.0), LEVEL_ICE_RGB, 6).mean() > 0.9
        assert np.mean([near(around(350.0, north), REGION_RGB, 40).any() for north in (620.0, 650.0, 680.0, 710.0,
                                                                                     740.0)]) >= 0.6
        panel = browser.execute_script("envPanel(lastFrame.environment, [150, 0]);"  # as a frame of that field shows it
                                       "return document.getElementById('env-values').innerText;")
        assert "drifted 150 m to 90.0°" in panel
    finally:
        browser.execute_script("map.applyFrame = window.applyFrame;")


def test_lay_open_water_from_the_page(exercise, browser):
    config, url, _ = exercise
    open_page(browser, url)
    names = browser.execute_script("return [...document.getElementById('ice-name').options].map((o) => o.value)")
    assert names == ["open water", "level ice 0.30 m"] == ctl_status(config)["ice"]
    view(browser, 700.0, 700.0, 1.0)
    x, y = (round(v) for v in canvas_pixel(browser, 700.0, 700.0))
    assert near(screenshot(browser)[y - 10:y + 11, x - 10:x + 11], LEVEL_ICE_RGB, 6).mean() > 0.9
    for field, value in (("ice-e0", "600"), ("ice-e1", "800"), ("ice-n0", "600"), ("ice-n1", "800")):
        browser.find_element("id", field).clear()
        browser.find_element("id", field).send_keys(value)
    browser.execute_script("document.getElementById('ice-name').value = 'open water';")
    browser.find_element("id", "set-ice").click()
    wait_until(lambda: browser.execute_script("return lastFrame.laid.length") > 0, 20, "the laid ice in a frame")
    assert browser.execute_script("return lastFrame.laid") == [[row, 6, 2, 0] for row in (6, 7)]  # 100 m tiles
    view(browser, 700.0, 700.0, 1.0)
    assert near(screenshot(browser)[y - 10:y + 11, x - 10:x + 11], WATER_RGB, 6).mean() > 0.9
    wait_until(lambda: "open water laid over E 600-800 m, N 600-800 m" in browser.find_element("id", "log").text, 10,
               "the command in the log")


def test_the_map_draws_the_convoy_red_while_too_close(exercise, browser):
    """A ship ahead in the picture, 250 m north of the own ship (frames given it here; the
    convoy's own test drives the real traffic picture): a dashed line to it, in the convoy's
    yellow beyond the limit and red under it."""
    browser.execute_script(
        "window.applyFrame = map.applyFrame;"
        "map.applyFrame = (h, a) => window.applyFrame.call(map, {...h, traffic: [{id: 230000001, x: h.ship.east,"
        " y: h.ship.north + 250, heading: 0, speed_kn: 6, length: 100, beam: 20}]}, a);")
    try:
        for limit, rgb in ((200.0, CONVOY_RGB), (400.0, SHIP_RGB)):
            browser.execute_script("map.geo.convoy = {ahead_mmsi: 230000001, astern_mmsi: null, min_distance_m: arguments[0]};",
                                   limit)
            ship = browser.execute_script("return [lastFrame.ship.east, lastFrame.ship.north]")
            view(browser, ship[0], ship[1] + 125.0, 1.0)
            image = screenshot(browser)
            x, y = (round(v) for v in canvas_pixel(browser, ship[0], ship[1] + 160.0))
            assert near(image[y - 30:y + 31, x - 3:x + 4], rgb, 30).any(), limit
    finally:
        browser.execute_script("map.applyFrame = window.applyFrame; map.geo.convoy = null;")


def test_freeze_and_resume_from_the_page(exercise, browser):
    config, url, _ = exercise
    open_page(browser, url)
    wait_until(lambda: not browser.execute_script("return lastFrame.environment.frozen"), 10, "a running exercise")
    browser.find_element("id", "freeze").click()
    wait_until(lambda: ctl_status(config)["frozen"], 20, "icebridge ctl status to say frozen")
    wait_until(lambda: not browser.find_element("id", "frozen-badge").get_attribute("hidden"), 5, "the FROZEN badge")
    before, node_before = shown_time(browser), ctl_status(config)["time_s"]
    time.sleep(1.0)
    assert shown_time(browser) == before, "the clock shown moved while frozen"
    assert ctl_status(config)["time_s"] == node_before, "the node's clock moved while frozen"
    assert "queued" in browser.find_element("css selector", "[data-for~=freeze]").text
    browser.find_element("id", "resume").click()
    wait_until(lambda: shown_time(browser) > before + 0.5, 20, "the clock shown to run again")
    status = ctl_status(config)
    assert not status["frozen"] and status["time_s"] > node_before


def test_reposition_from_the_page(exercise, browser):
    from selenium.webdriver.common.action_chains import ActionChains

    config, url, _ = exercise
    open_page(browser, url)
    view(browser, 400.0, 400.0, 0.6)
    target = (250.0, 600.0)  # east, north: in the ice, away from the ship's lane
    px, py = canvas_pixel(browser, *target)
    canvas = browser.find_element("id", "map")
    rect = browser.execute_script("const r = map.canvas.getBoundingClientRect(); return [r.left, r.top, r.width, r.height];")
    browser.find_element("id", "pick").click()
    ActionChains(browser).move_to_element_with_offset(canvas, px - rect[0] - rect[2] / 2,
                                                      py - rect[1] - rect[3] / 2).click().perform()
    picked = [float(browser.find_element("id", i).get_attribute("value")) for i in ("rp-east", "rp-north")]
    assert math.dist(picked, target) < 3.0, f"picked {picked}, clicked on {target}"
    for field, value in (("rp-heading", "90"), ("rp-speed", "6")):
        browser.find_element("id", field).clear()
        browser.find_element("id", field).send_keys(value)
    browser.find_element("id", "reposition").click()
    status = wait_until(lambda: (s := ctl_status(config)) and math.dist((s["east_m"], s["north_m"]), picked) < 20 and s,
                        30, "the node's ship at the picked place")
    assert abs(status["heading_deg"] - 90.0) < 5.0
    wait_until(lambda: math.dist(browser.execute_script("return [lastFrame.ship.east, lastFrame.ship.north]"), picked)
               < 20, 10, "the page's ship at the picked place")
    request(endpoint_of(config), {"command": {"command": "freeze"}}, None)
    try:
        wait_until(lambda: browser.execute_script("return lastFrame.environment.frozen"), 10, "the page frozen")
        ship = browser.execute_script("return [lastFrame.ship.east, lastFrame.ship.north]")
        view(browser, 400.0, 400.0, 0.6)
        image = screenshot(browser)
        x, y = (round(v) for v in canvas_pixel(browser, *ship))
        assert near(image[y - 4:y + 5, x - 4:x + 5], SHIP_RGB, 20).mean() > 0.5, "no ship drawn at its new place"
        assert "reposition" in browser.find_element("id", "log").text
    finally:
        request(endpoint_of(config), {"command": {"command": "resume"}}, None)


def test_a_refused_command_is_shown(exercise, browser):
    _, url, _ = exercise
    open_page(browser, url)
    box = browser.find_element("id", "visibility")
    box.clear()
    box.send_keys("20")  # below the node's 50 m: the browser's own check is bypassed by submitting through JS
    browser.execute_script("document.getElementById('visibility-form').dispatchEvent(new Event('submit', {cancelable: true}))")
    reply = browser.find_element("css selector", "[data-for~=visibility]")
    wait_until(lambda: "visibility_m" in reply.text, 10, "the node's refusal on the page")
    assert "50" in reply.text and "err" in reply.get_attribute("class")


def test_links_sensor_failures_and_a_save_point_from_the_page(exercise, browser):
    config, url, folder = exercise
    open_page(browser, url)
    text = lambda element: browser.find_element("id", element).text
    state = lambda: browser.execute_script(  # the link's state badge: its text and background colour
        "const s = document.querySelector('#links [data-link=instruments] .state');"
        "return s && [s.textContent, getComputedStyle(s).backgroundColor.match(/\\d+/g).map(Number)];")

    def apply(form: str, **fields: str) -> None:  # set a form's fields as if chosen, and click its button
        browser.execute_script("for (const [k, v] of Object.entries(arguments[1])) { const e = document.getElementById(k);"
                               "e.value = v; e.dispatchEvent(new Event('change')); }"
                               "document.querySelector(`#${arguments[0]} button`).click();", form, fields)

    def logged(what: str) -> str:
        return wait_until(lambda: what in (t := text("log")) and t, 15, f"{what!r} in the event log")

    assert wait_until(state, 20, "the link in the Links card")[0] == "up"
    assert not browser.find_element("id", "failure-ship-row").is_displayed()  # one own ship: no choice
    try:
        apply("link-fault-form", **{"lf-link": "instruments", "lf-fault": "disconnect"})
        wait_until(lambda: (h := ctl_status(config)["links"][0])["fault"] == "disconnect" and not h["connected"], 20,
                   "the node's link disconnected")
        red, green, blue = wait_until(lambda: (s := state())[0] == "down" and s, 15, "the link down on the page")[1]
        assert red > 2 * green and red > 2 * blue, "a link down is not shown red"
        assert "link instruments: fault disconnect" in logged("link instruments down") and "node alarm" in text("alarms")
        apply("link-fault-form", **{"lf-fault": "none"})
        wait_until(lambda: state()[0] == "up", 30, "the link up again on the page")
        logged("link instruments up")
        apply("gyro-form", **{"gyro-mode": "offset", "gyro-offset": "-12.5"})
        apply("gnss-form", **{"gnss-mode": "jumping", "gnss-jump": "500"})
        wait_until(lambda: ctl_status(config)["sensors"] == {"gyro": "offset", "gnss": "jumping", "log": "ok"}, 20,
                   "the node's gyro offset and GNSS jumping")
        assert "sensor failure: GNSS position jumping 500 m" in logged("sensor failure: gyro offset -12.5 deg")
        wait_until(lambda: "sensor: gyro offset" in text("alarms"), 10, "the gyro among the alarms")
        assert "gyro offset, GNSS jumping" in text("failures-now")
        apply("gyro-form", **{"gyro-mode": "ok"})
        apply("gnss-form", **{"gnss-mode": "ok"})
        wait_until(lambda: "sensor:" not in text("alarms"), 20, "the sensor alarms cleared")
    finally:  # the other tests find the link up and the sensors well
        for command in ({"command": "link_fault", "link": "instruments", "fault": "none"},
                        {"command": "sensor_failure", "sensor": "gyro", "mode": "ok"},
                        {"command": "sensor_failure", "sensor": "gnss", "mode": "ok"}):
            request(endpoint_of(config), {"command": command}, None)
    apply("save-form", **{"save-name": "from-the-page"})
    path = Path(wait_until(lambda: "writes" in (t := text("save-reply")) and t.rsplit(" ", 1)[1], 10, "the save's path"))
    point = wait_until(lambda: path.is_file() and read_save(path), 20, "the save point written")
    assert path.parents[2] == (folder / "sessions").resolve() and point.seq > 0 and "save point" in text("log")


def test_token_asked_with_the_network_opened(exercise, tmp_path, browser):
    config, _, folder = exercise
    stream = [int(line.rsplit(":", 1)[1].rstrip('"')) for line in config.read_text().splitlines()
              if line.startswith(("publish", "snapshot"))]
    port = free_port()
    guarded = write_config(folder, tuple(stream), int(endpoint_of(config).rsplit(":", 1)[1]), port,
                           extra=f'token = "{TOKEN}"\n')
    station = start(folder, "guarded", "instructor", "--config", str(guarded))
    url = f"http://127.0.0.1:{port}/"
    try:
        wait_until(lambda: station.poll() is None and http(url)[0] == 401, 120, "the guarded station")
        assert "Access token" in http(url)[1]
        assert http(url + "static/station.js")[0] == 401
        assert http(url, {"Authorization": f"Bearer {TOKEN}"})[0] == 200
        assert http(url + "?token=wrong-token-0123456789")[0] == 401
        websocket_refused(port)
        assert websocket_hello(port, TOKEN)["type"] == "hello"
        browser.get(url)  # the login page, then the station with the token's cookie
        browser.find_element("id", "t").send_keys(TOKEN + "\n")
        wait_until(lambda: browser.execute_script("return !!window.stationStats && window.stationStats.frames > 2"),
                   30, "frames after signing in")
    finally:
        stop(station)
        browser.delete_all_cookies()


def test_user_errors_are_clean(exercise):
    config, url, _ = exercise
    port = int(url.rsplit(":", 1)[1].strip("/"))
    for args, text in ((["--record", "nowhere"], "no nmea.log"), (["--export", "p.png"], "--record DIR"),
                       (["--port", "0"], "--port"),
                       (["--port", str(port)], "cannot listen")):
        done = subprocess.run([sys.executable, "-m", "bridge_node", "instructor", "--config", str(config), *args],
                              cwd=REPO, capture_output=True, text=True, timeout=120)
        assert done.returncode == 2 and text in done.stderr and "Traceback" not in done.stderr, done.stderr
    opened = config.with_name("opened.toml")  # a network address without allow_network
    opened.write_text(config.read_text().replace("[instructor]\n", '[instructor]\nhost = "10.1.2.3"\n'))
    done = subprocess.run([sys.executable, "-m", "bridge_node", "instructor", "--config", str(opened)],
                          cwd=REPO, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "not a loopback address" in done.stderr and "Traceback" not in done.stderr


def test_debrief_of_the_session_record(exercise, browser, tmp_path):
    config, _, folder = exercise
    record = next((folder / "sessions").iterdir())  # the running node's record, with this module's commands
    plots = tmp_path / "plots.png"
    done = subprocess.run([sys.executable, "-m", "bridge_node", "instructor", "--config", str(config), "--record",
                           str(record), "--export", str(plots)], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["events"] >= 4  # freeze, resume, reposition... of the tests before
    image = np.asarray(Image.open(plots).convert("L"))
    assert image.shape == (900, 1000) and (image < 128).mean() > 0.01, "a blank plot"
    port = free_port()
    station = start(folder, "debrief", "instructor", "--config", str(config), "--record", str(record),
                    "--port", str(port))
    try:
        url = f"http://127.0.0.1:{port}/"
        wait_until(lambda: station.poll() is None and http(url)[0] == 200, 120, "the debrief page")
        assert http(url + "plots.png")[1][1:4] == "PNG"
        browser.get(url)
        wait_until(lambda: browser.execute_script("return !!(playback.data && map.frame)"), 90, "the record played")
        assert browser.find_element("id", "debrief-card").is_displayed()
        assert not browser.find_element("id", "freeze").is_displayed()
        duration = browser.execute_script("return playback.data.duration")
        browser.execute_script("seekTo(arguments[0]); map.setFollow(true);", duration)
        wait_until(lambda: "reposition" in browser.find_element("id", "log").text, 10, "the commands in the log")
        end = browser.execute_script("return [map.frame.ship.east, map.frame.ship.north]")
        assert math.dist(end, browser.execute_script("return [playback.data.a.pos_east.at(-1), "
                                                     "playback.data.a.pos_north.at(-1)]")) < 1.0
        laid = []  # the open water laid in the north-east corner (test_lay_open_water_from_the_page)
        for t in (duration, 0.0):
            draws = browser.execute_script("return window.stationStats.draws")
            browser.execute_script("seekTo(arguments[0]); map.setFollow(false); map.cx = 700; map.cy = 700;"
                                   "map.scale = 1; map.dirty = true;", t)
            wait_until(lambda: browser.execute_script("return window.stationStats.draws") > draws, 10, "a redraw")
            x, y = (round(v) for v in canvas_pixel(browser, 700.0, 700.0))
            laid.append(near(screenshot(browser)[y - 10:y + 11, x - 10:x + 11], WATER_RGB, 6).mean())
        assert laid[0] > 0.9 and laid[1] < 0.1, laid  # water after the command, level ice before it
        assert "reposition" not in browser.find_element("id", "log").text
        browser.find_element("id", "speed").send_keys("1000")
        browser.find_element("id", "play").click()
        wait_until(lambda: browser.execute_script("return playback.t") >= duration, 10, "the playback at its end")
        x, y = (round(v) for v in canvas_pixel(browser, *browser.execute_script(
            "return [map.frame.ship.east, map.frame.ship.north]")))
        assert near(screenshot(browser)[y - 4:y + 5, x - 4:x + 5], SHIP_RGB, 20).mean() > 0.5
    finally:
        stop(station)
