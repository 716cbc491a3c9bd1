"""Fuzz tests of the parsers the other fuzz files leave (issue 30): scenario TOML files
mutated as a careless integrator would edit them, and state-stream messages (the codec,
then ``WorldView.apply``) with hostile header fields and array frames. A parser passes when
it returns or raises its documented error (``ConfigError`` naming the file; ``CodecError``),
never hangs (pytest's timeout), and a message it accepts applies to a view with every pose
finite and every row within the view. Budget: ``conftest.fuzz_budget``."""
import json
import math
import tomllib

import numpy as np
import pytest
import tomli_w
from conftest import REPO, exercise_config, fuzz_budget
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from toml_mutants import mutants, mutated, paths_of

from bridge_node.hil.scenario import load_scenario
from bridge_node.node.config import ConfigError
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.stream.codec import CodecError, decode, encode
from bridge_node.stream.world_view import WorldView
from sim_core.world import snapshot, step

SCENARIOS = sorted((REPO / "config" / "scenarios").glob("*.toml"))
FUZZ = settings(max_examples=fuzz_budget(300), deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@FUZZ
@given(st.sampled_from(SCENARIOS), st.data())
def test_fuzz_mutated_scenarios_are_clean_errors_or_valid_scenarios(tmp_path, seed, data):
    doc = mutated(tomllib.loads(seed.read_text()), data)
    path = tmp_path / "mutant.toml"
    try:
        path.write_text(tomli_w.dumps(doc))
    except (TypeError, ValueError):
        return  # not expressible as TOML: nothing a user could write
    try:
        scenario = load_scenario(path)
    except ConfigError as exc:
        assert str(path) in str(exc)
        return
    assert scenario.end_s <= 3600.0 + 600.0 and all(math.isfinite(e.end_s) for e in scenario.expect)
    assert scenario.kinds is None or len(scenario.kinds) == len(scenario.links)


@pytest.fixture(scope="module")
def stream_world(tmp_path_factory):
    cfg = exercise_config(tmp_path_factory.mktemp("fuzz") / "tiles", 400.0, 400.0, start_north=-60.0)
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    first = snapshot(model, data)
    for _ in range(30):
        events = step(model, data, 0.1)
    return first, events


HEADER_VALUES = st.one_of(mutants(), st.integers(-2**70, 2**70), st.floats(allow_nan=True, allow_infinity=True),
                          st.text(max_size=8))


@FUZZ
@given(st.data())
def test_fuzz_state_messages_are_codec_errors_or_apply_within_the_view(stream_world, data):
    first, events = stream_world
    frames = encode(events, 1.0)
    header = json.loads(frames[1])
    if data.draw(st.booleans()):
        header = mutated(header, data) if data.draw(st.booleans()) else header
        path = data.draw(st.sampled_from(list(paths_of(header))))
        parent = header
        for key in path[:-1]:
            parent = parent[key]
        parent[path[-1]] = data.draw(HEADER_VALUES)
        frames = [frames[0], json.dumps(header).encode(), *frames[2:]]
    else:
        k = data.draw(st.integers(2, len(frames) - 1))
        frame = bytearray(frames[k])
        if frame and data.draw(st.booleans()):
            frame[data.draw(st.integers(0, len(frame) - 1))] = data.draw(st.integers(0, 255))
        else:
            frame = bytearray(data.draw(st.binary(max_size=64)))
        frames = [*frames[:k], bytes(frame), *frames[k + 1:]]
    try:
        got, _, _ = decode(frames)
    except CodecError:
        return
    view = WorldView()
    view.apply(first)
    view.apply(got)
    assert np.isfinite(view.pose).all() and view.rows <= max(first.floe_rows.max(initial=0) + 1, view.rows)
    assert math.isfinite(view.ship.north) and math.isfinite(view.time)
