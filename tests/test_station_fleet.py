"""The instructor station of an exercise with two own ships (issue 31, escort and convoy):
the instructor chooses which ship a steering, engine or sensor failure goes to, the node
fails that ship alone (``icebridge ctl status``), and the page shows the chosen ship's
failures and names the other ship's alarms. ``icebridge run`` and ``icebridge instructor``
in their own processes on loopback; the page in headless Chromium (Debian's, Selenium)."""
from __future__ import annotations

import pytest

from bridge_node.common.network import free_port
from bridge_node.station.harness import chromium, ctl_status, node_and_station, open_page, require_chromium, \
    wait_until
from station_helpers import write_config

require_chromium()  # a failure, not a skip: the browser checks must run wherever the suite does
FOLLOWER = ('[[ships]]\nname = "polar_cargo"\nmmsi = 230000002\nais_name = "FOLLOWER"\nstart_north = -20.0\n'
            'start_east = 250.0\n[[ships.links]]\nname = "follower_instruments"\ntype = "nmea0183"\n'
            'udp_port = {port}\n')


@pytest.fixture(scope="module")
def fleet_station(tmp_path_factory):
    """A running node with two own ships and a station on it, the page open: (config, browser)."""
    folder = tmp_path_factory.mktemp("station_fleet")
    stream, control, port = (free_port(), free_port()), free_port(), free_port()
    config = write_config(folder, stream, control, port)
    text = config.read_text().replace('[ship]\nname = "polar_cargo"\n', '[ship]\nname = "polar_cargo"\nmmsi = 230000001\n')
    config.write_text(text + FOLLOWER.format(port=free_port()))
    url = f"http://127.0.0.1:{port}/"
    with node_and_station(folder, config, f"tcp://127.0.0.1:{control}", url, "--render", "none", "--duration", "600",
                          "--no-record"), chromium() as browser:
        open_page(browser, url)
        yield config, browser


def test_the_instructor_fails_the_ship_chosen_and_sees_its_failures(fleet_station):
    config, browser = fleet_station
    text = lambda element: browser.find_element("id", element).text

    def apply(form: str, **fields: str) -> None:  # set a form's fields as if chosen, and click its button
        browser.execute_script("for (const [k, v] of Object.entries(arguments[1])) { const e = document.getElementById(k);"
                               "e.value = v; e.dispatchEvent(new Event('change')); }"
                               "document.querySelector(`#${arguments[0]} button`).click();", form, fields)

    def choose(ship: int) -> None:
        browser.execute_script("const s = document.getElementById('failure-ship'); s.value = arguments[0];"
                               "s.dispatchEvent(new Event('change'));", str(ship))

    options = wait_until(lambda: browser.execute_script(
        "return [...document.getElementById('failure-ship').options].map((o) => o.text);"), 20, "the ship choice")
    assert options == ["POLAR CARGO", "FOLLOWER (ship 1)"]
    assert browser.find_element("id", "failure-ship-row").is_displayed()
    choose(1)
    apply("engine-form", **{"engine-power": "0"})
    apply("steering-form", steering="2")
    apply("gyro-form", **{"gyro-mode": "offset", "gyro-offset": "7"})
    status = wait_until(lambda: (s := ctl_status(config))["other_ships"][0]["power_percent"] == 0.0
                        and s["other_ships"][0]["steering_pumps"] == 0
                        and s["other_ships"][0]["sensors"]["gyro"] == "offset" and s, 20,
                        "the second ship's engine, steering and gyro failed")
    assert (status["power_percent"], status["steering_pumps"], status["sensors"]["gyro"]) == (100.0, 2, "ok")
    wait_until(lambda: "both pumps failed, engine 0 % power; gyro offset" in text("failures-now"), 10,
               "the second ship's failures on the page")
    alarms = wait_until(lambda: "ship 1: engine: blackout" in (t := text("alarms")) and t, 10,
                        "the second ship's alarm")
    assert "ship 1: steering gear: rudder stuck" in alarms and "ship 1: sensor: gyro offset" in alarms
    assert not any(line.startswith("engine:") for line in alarms.splitlines())  # the first ship's engine works
    wait_until(lambda: "ship 1: engine failure: blackout" in text("log"), 10, "the failure in the event log")
    choose(0)
    wait_until(lambda: "both pumps working, engine 100 % power" in text("failures-now"), 10,
               "the first ship's failures on the page")
    choose(1)
    apply("engine-form", **{"engine-power": "100"})
    apply("steering-form", steering="0")
    apply("gyro-form", **{"gyro-mode": "ok"})
    wait_until(lambda: "ship 1:" not in text("alarms"), 20, "the second ship's alarms cleared")
    status = ctl_status(config)["other_ships"][0]
    assert (status["power_percent"], status["steering_pumps"], status["sensors"]["gyro"]) == (100.0, 2, "ok")
