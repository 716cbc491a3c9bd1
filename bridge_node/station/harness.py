"""The station as its tests and benchmark run it: ``icebridge`` commands (a node, a station)
in their own processes on loopback, waited for and ended, and Debian's Chromium, headless,
driven by Selenium (a development dependency, imported only here) on the station's page."""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TypeVar

from bridge_node.control.client import request

T = TypeVar("T")
CHROMIUM, DRIVER = shutil.which("chromium"), shutil.which("chromedriver")


def require_chromium() -> None:
    """RuntimeError if Chromium or its driver is missing (the station's checks fail, not skip)."""
    if not (CHROMIUM and DRIVER):
        raise RuntimeError("the instructor station's tests need chromium and chromium-driver: run scripts/setup.sh, "
                           "which installs them")


def wait_until(predicate: Callable[[], T], timeout: float, what: str, every: float = 0.1) -> T:
    """The predicate's first truthy value, polled until ``timeout`` s; fails naming ``what``."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")
        time.sleep(every)


def start(folder: Path, name: str, *args: str) -> subprocess.Popen:
    """``icebridge ARGS`` in its own process, its output in ``folder/NAME.log``."""
    with open(folder / f"{name}.log", "w") as out:
        return subprocess.Popen([sys.executable, "-m", "bridge_node", *args], stdout=out, stderr=subprocess.STDOUT,
                                env={**os.environ, "ICEBRIDGE_TOKEN": ""})


def stop(proc: subprocess.Popen) -> None:
    """End a process started here: SIGTERM, then SIGKILL after 15 s."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)


def answers(endpoint: str) -> bool:
    """Whether a node's control endpoint answers a status request."""
    try:
        return bool(request(endpoint, {"request": "status"}, None, 1.0).get("ok"))
    except Exception:  # noqa: BLE001 -- not up yet
        return False


def http(url: str, headers: dict | None = None) -> tuple[int, str]:
    """The HTTP status and text of a GET (0 and "" where nothing answers)."""
    try:
        with urllib.request.urlopen(urllib.request.Request(url, headers=headers or {}), timeout=5) as r:
            return r.status, r.read().decode("latin-1")
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read().decode("latin-1")
    except OSError:
        return 0, ""


def ctl_status(config: Path) -> dict:
    """The node's status as ``icebridge ctl status`` prints it."""
    done = subprocess.run([sys.executable, "-m", "bridge_node", "ctl", "--config", str(config), "status"],
                          capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@contextlib.contextmanager
def node_and_station(folder: Path, config: Path, endpoint: str, url: str, *run_args: str) -> Iterator[None]:
    """``icebridge run --config CONFIG RUN_ARGS`` and ``icebridge instructor`` on it, until the
    node's control ``endpoint`` answers and the station serves ``url``; both ended after,
    with the last of their logs printed."""
    node = start(folder, "node", "run", "--config", str(config), *run_args)
    station = start(folder, "station", "instructor", "--config", str(config))
    try:
        wait_until(lambda: node.poll() is None and answers(endpoint), 180, "the node's control endpoint")
        wait_until(lambda: station.poll() is None and http(url)[0] == 200, 120, "the station's page")
        yield
    finally:
        stop(station)
        stop(node)
        for name in ("node", "station"):
            print(name, (folder / f"{name}.log").read_text()[-2000:])


@contextlib.contextmanager
def chromium(width: int = 1400, height: int = 900) -> Iterator[object]:
    """Headless Chromium (Selenium's ``webdriver.Chrome``), one CSS pixel a pixel."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    require_chromium()
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                f"--window-size={width},{height}", "--force-device-scale-factor=1"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(DRIVER), options=options)
    driver.set_page_load_timeout(30)
    try:
        yield driver
    finally:
        driver.quit()


def open_page(browser, url: str, floes: int = 1, timeout: float = 60.0) -> None:
    """Open the station's page and wait for frames with at least ``floes`` live floes."""
    browser.get(url)
    wait_until(lambda: browser.execute_script("return window.stationStats && window.stationStats.frames > 3 && "
                                              f"window.stationStats.floes >= {floes}"), timeout,
               f"frames with at least {floes} live floes on the page")
