"""The state stream against bad messages (issue 30, item 8): a message that decodes but does
not fit a view is refused by the codec (and so counted by every subscriber), the JSON header
cannot blow the stack or overflow, and the physics process's handover to the publisher is a
private IPC socket where a bad message is counted and the stream goes on."""
import dataclasses
import json
import os
import stat

import numpy as np
import pytest
from conftest import exercise_config

from bridge_node.common.network import free_port
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.stream.codec import MAX_ROWS, TOPIC, CodecError, decode, encode
from bridge_node.stream.publisher import StatePublisher
from bridge_node.stream.settings import StreamSettings
from bridge_node.stream.subscriber import StateSubscriber
from sim_core.ice.bending import CRACK_EVENT
from sim_core.ice.floes import FROZEN_CRACK
from sim_core.scene.switches import FROZEN_FLOE_EVENT
from sim_core.world import snapshot, step


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    cfg = exercise_config(tmp_path_factory.mktemp("hard") / "tiles", 400.0, 400.0, start_north=-60.0)
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    for _ in range(30):
        events = step(model, data, 0.1)  # floes broken: rows, poses
    return model, data, events


def _with_header(frames: list, **changes) -> list:
    header = json.loads(frames[1]) | changes
    return [frames[0], json.dumps(header).encode(), *frames[2:]]


def test_messages_out_of_a_views_bounds_are_codec_errors(world):
    model, data, events = world
    assert len(events.floe_rows) > 0
    bad = {
        "row out of range": dataclasses.replace(events, floe_rows=events.floe_rows + MAX_ROWS),
        "negative row": dataclasses.replace(events, broken_by_hull=np.array([-5])),
        "NaN pose": dataclasses.replace(events, floe_pose=np.where(np.ones_like(events.floe_pose, bool), np.nan, 0)),
        "lengths": dataclasses.replace(events, floe_status=events.floe_status[:-1]),
        "placement": dataclasses.replace(events, thawed=np.array([1 << 40])),
        "ship": dataclasses.replace(events, ship=dataclasses.replace(events.ship, north=float("inf"))),
        "cracked row": dataclasses.replace(events, cracked=np.array([(MAX_ROWS + 1, 3)], dtype=CRACK_EVENT)),
        "frozen crack cell": dataclasses.replace(events, frozen_cracks=np.array([(0, MAX_ROWS + 1, 3)],
                                                                               dtype=FROZEN_CRACK)),
        "frozen floe cell": dataclasses.replace(events, frozen_floes=np.array([(0, MAX_ROWS + 1, 1, np.zeros(6))],
                                                                             dtype=FROZEN_FLOE_EVENT)),
    }
    for what, message in bad.items():
        with pytest.raises(CodecError):
            decode(encode(message))
        assert what
    good = encode(events, 1.5)
    assert decode(good)[0].seq == events.seq
    for frames in (_with_header(good, time=10 ** 400),  # an integer no float holds
                   [TOPIC, b"[" * 100_000 + b"]" * 100_000, *good[2:]],  # nested past the stack
                   _with_header(good, input_time=float("nan")),
                   _with_header(good, environment={"visibility": -1.0}),
                   _with_header(good, arrays=[["<i8", [2 ** 40]]] * (len(good) - 3)),
                   _with_header(good, arrays=[["<M8[s]" if k == 14 else d, shape]  # a date array (fuzz found it)
                                              for k, (d, shape) in enumerate(json.loads(good[1])["arrays"])]),
                   _with_header(good, ice_offset=[1.0]), _with_header(good, ice_offset=[1.0, float("inf")]),
                   _with_header(good, ice_offset=[True, 0.0]),
                   _with_header(good, ship=json.loads(good[1])["ship"] | {"north": ""})):  # text for a number
        with pytest.raises(CodecError):
            decode(frames)


def test_the_handover_is_private_and_a_bad_message_is_counted_not_fatal(world):
    model, data, _ = world
    settings = StreamSettings(publish=f"tcp://127.0.0.1:{free_port()}", snapshot=f"tcp://127.0.0.1:{free_port()}")
    with StatePublisher(settings) as publisher:
        folder = publisher._folder
        assert stat.S_IMODE(os.stat(folder).st_mode) == 0o700  # this user's processes only
        publisher.publish(snapshot(model, data))
        with StateSubscriber(settings.publish, settings.snapshot) as sub:
            sub.sync()
            for junk in ([TOPIC, b"{not json"], [b"w", b"{}"], [TOPIC, b"[" * 50_000]):
                publisher._push.send_multipart(junk)
            for _ in range(5):
                publisher.publish(step(model, data, 0.1))
            sub.catch_up(10.0)
            assert sub.view.seq == data.seq  # the stream went on past the junk
        assert publisher.malformed == 3 and publisher.error is None
    assert not folder.exists()  # the private folder goes with the publisher
