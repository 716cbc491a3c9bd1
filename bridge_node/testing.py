"""pytest fixtures for your own hardware-in-the-loop tests, with the console, the bench and
the expectations of ``icebridge hil run``.

Enable them in your ``conftest.py`` with ``pytest_plugins = ["bridge_node.testing"]`` (or
run ``pytest -p bridge_node.testing``), then::

    def test_helm(hil_bench, hil_scenario):
        bench = hil_bench(links=["can"], node_config="my_node.toml")
        result = bench.play(hil_scenario("config/scenarios/helm_response.toml"))
        assert_scenario(result)

``hil_scenario`` takes a scenario file or the same content as a dict. Needs socat (pty pairs).
"""
from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import ExitStack
from pathlib import Path

import pytest

from bridge_node.hil.bench import Bench
from bridge_node.hil.player import ScenarioResult
from bridge_node.hil.report import result_lines
from bridge_node.hil.scenario import Scenario, load_scenario


class PlayableScenario:
    """A scenario with the name reports give its source."""

    def __init__(self, scenario: Scenario, path: str) -> None:
        self.scenario, self.path = scenario, path


class TestBench:
    """A started bench (``Bench``) whose ``play`` takes a ``PlayableScenario``."""

    __test__ = False  # not a test class, despite its name

    def __init__(self, bench: Bench) -> None:
        self.bench = bench

    def stop(self) -> dict | None:
        """Stop the node and the console; the node's JSON summary (links, errors, alarms)."""
        self.bench.__exit__(None, None, None)
        return self.bench.node_summary

    def play(self, playable: PlayableScenario) -> ScenarioResult:
        return self.bench.play(playable.scenario, playable.path)


def assert_scenario(result: ScenarioResult) -> None:
    """AssertionError with the report's lines unless every expectation was met."""
    assert result.passed, "\n".join(result_lines(result))


@pytest.fixture
def hil_bench(tmp_path: Path) -> Iterator[Callable[..., TestBench]]:
    """A factory: ``hil_bench(links=["can"], node_config=None, startup_timeout_s=180.0)``
    starts the node process and the console (link kinds: can, nmea0183, modbus) in a folder
    of ``tmp_path``; every bench started is stopped at the end of the test."""
    with ExitStack() as stack:
        count = [0]

        def start(links: list[str] = ("can",), node_config: str | Path | None = None,
                  startup_timeout_s: float = 180.0) -> TestBench:
            count[0] += 1
            folder = tmp_path / f"bench{count[0]}"
            bench = stack.enter_context(Bench(folder, list(links), str(node_config) if node_config else None,
                                              startup_timeout_s))
            return TestBench(bench)
        yield start


@pytest.fixture
def hil_scenario() -> Callable[[str | Path | dict], PlayableScenario]:
    """``hil_scenario(path_or_dict)``: a scenario file, or a dict of the same content."""

    def make(source: str | Path | dict) -> PlayableScenario:
        if isinstance(source, dict):
            return PlayableScenario(Scenario.model_validate(source), f"<{source.get('name', 'scenario')}>")
        return PlayableScenario(load_scenario(source), str(source))
    return make
