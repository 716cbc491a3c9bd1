"""The state stream on loopback: messages round-trip exactly, late joiners and lossy
subscribers end up with the published state, render processes (separate processes) draw
what a single process draws, and a slow renderer never holds the physics back."""
import dataclasses
import json
import math
import os
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest
import zmq
from conftest import REPO, exercise_toml, free_port
from links_helpers import node_config, wait_for
from PIL import Image
from pyais import decode as ais_decode
from test_links_ais import QUIET
from test_links_dis import datagrams, other_simulator_pdu, receiver

from bridge_node.exercise.listeners import StreamOutput
from bridge_node.exercise.tick import TickOutcome
from bridge_node.links.hub import LinkHub
from bridge_node.node.config import load_config
from bridge_node.node.realtime_loop import run_realtime
from bridge_node.node.render_processes import RenderProcesses
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet, create_context
from bridge_node.render.renderer import SceneRenderer
from bridge_node.stream.codec import decode, encode
from bridge_node.stream.publisher import StatePublisher
from bridge_node.stream.subscriber import StateSubscriber
from bridge_node.stream.world_view import TRAFFIC_DTYPE, WorldView
from sim_core.frames.geodesy import geodetic_to_local
from sim_core.world import Controls, snapshot, step

CHANNELS = ('[[render.channels]]\nname = "bow"\nwidth = 160\nheight = 90\npitch_deg = -10.0\nblend_right_deg = 5.0\n'
            '[[render.channels]]\nname = "aft"\nwidth = 160\nheight = 90\nyaw_deg = 180.0\npitch_deg = -25.0\n'
            'eye = [-75.0, 0.0, 20.0]\n')


@pytest.fixture(scope="module")
def exercise(tmp_path_factory):
    """Config file, config and world of a small exercise with two channels."""
    folder = tmp_path_factory.mktemp("stream")
    path = exercise_toml(folder, CHANNELS)
    cfg = load_config(path)
    return path, cfg, build_world(cfg, str(path))


def views_equal(a: WorldView, b: WorldView) -> None:
    assert a.seq == b.seq and a.rows == b.rows and a.placements == b.placements and a.frozen == b.frozen
    np.testing.assert_array_equal(a.status, b.status)
    np.testing.assert_array_equal(a.cause, b.cause)
    np.testing.assert_allclose(a.pose, b.pose, atol=2e-4)  # float32 on the wire


def test_messages_round_trip(exercise):
    _, cfg, model = exercise
    data = start_world(model, cfg)
    for _ in range(300):
        events = step(model, data, 0.1, Controls(rudder=1.0))  # clamped: a rejection travels too
    traffic = np.array([(230000001, 120.5, -40.25, 1.5, 5.1, 110.0, 24.0)], dtype=TRAFFIC_DTYPE)
    back, input_time, back_traffic = decode(encode(events, 12.5, traffic))
    assert input_time == 12.5 and back.seq == events.seq and back.ship == events.ship
    np.testing.assert_array_equal(back_traffic, traffic)
    assert decode(encode(events))[2].shape == (0,)
    drifted = dataclasses.replace(events, ice_offset=(12.25, -3.5))  # where a drifting field's frame lies
    assert decode(encode(drifted))[0].ice_offset == (12.25, -3.5)
    assert back.rejected == events.rejected and len(back.placed.tile) == len(events.placed.tile)
    np.testing.assert_array_equal(back.floe_rows, events.floe_rows)
    np.testing.assert_allclose(back.floe_pose, events.floe_pose, atol=2e-4)
    full = WorldView()
    full.apply(decode(encode(snapshot(model, data)))[0])
    direct = WorldView()
    direct.apply(snapshot(model, data))
    views_equal(full, direct)


def test_late_joiner_and_lost_messages_end_with_the_published_state(exercise):
    _, cfg, model = exercise
    data = start_world(model, cfg)
    with StatePublisher(cfg.stream) as publisher:
        for _ in range(200):  # the channel is broken before anyone listens
            publisher.publish(step(model, data, 0.1))
        with StateSubscriber(cfg.stream.publish, cfg.stream.snapshot) as late, \
                StateSubscriber(cfg.stream.publish, cfg.stream.snapshot) as lossy:
            late.sync()
            lossy.sync()
            deadline = time.monotonic() + 10.0  # a snapshot may predate the last steps; they follow on the stream
            while late.view.seq < 200 and time.monotonic() < deadline:
                late.poll(50)
            assert late.view.seq == 200 and late.view.take_changes().broken.size > 100
            for _ in range(150):
                publisher.publish(step(model, data, 0.1))
                # each waits for the step just published, so a resync's snapshot does not jump
                # past the next drop (on a loaded machine the sender may run ahead of a short wait)
                late.poll(50)
                lossy.poll(50, drop=lambda seq: seq % 17 == 0 or 280 <= seq < 290)  # every 17th and a burst
            deadline = time.monotonic() + 10.0
            while min(late.view.seq, lossy.view.seq) < data.seq and time.monotonic() < deadline:
                late.poll(50)
                lossy.poll(50, drop=lambda seq: seq % 17 == 0)
            truth = WorldView()
            truth.apply(decode(encode(snapshot(model, data)))[0])
            views_equal(late.view, truth)
            views_equal(lossy.view, truth)
            assert lossy.resyncs >= 8 and lossy.lost >= 8
    assert publisher.dropped == 0 and publisher.snapshots >= 10


def test_catching_up_at_the_end_reaches_the_last_step_published(exercise):
    """A renderer told to finish right after the node's last step still draws that step:
    it waits for the publisher's heartbeats, which name the last step sent."""
    _, cfg, model = exercise
    data = start_world(model, cfg)
    with StatePublisher(cfg.stream) as publisher:
        publisher.publish(snapshot(model, data))
        with StateSubscriber(cfg.stream.publish, cfg.stream.snapshot) as sub:
            sub.sync()
            for _ in range(30):
                publisher.publish(step(model, data, 0.1))
            applied = sub.catch_up(10.0)
            assert sub.view.seq == data.seq and sub.heartbeats >= 2
            assert [e.seq for e in applied] == list(range(data.seq - len(applied) + 1, data.seq + 1))


def test_the_publisher_process_that_dies_is_reported_and_the_physics_goes_on(exercise):
    """The publisher runs in its own process: a second one on the same endpoints cannot
    bind (ZMQError, as the first holds them); killed, it is named in ``error`` with its
    exit code, and publishing on goes on without blocking (counted as dropped once the
    handover is full)."""
    _, cfg, model = exercise
    data = start_world(model, cfg)
    with StatePublisher(cfg.stream) as publisher:
        with pytest.raises(zmq.ZMQError):
            StatePublisher(cfg.stream).open()
        publisher.publish(step(model, data, 0.1))
        assert publisher.error is None
        publisher._process.kill()
        publisher._process.join(10.0)
        assert "exit code -9" in publisher.error
        events = step(model, data, 0.1)
        for _ in range(1200):  # beyond the handover's high-water mark: dropped, never waited for
            publisher.publish(events)
    assert publisher.dropped > 0 and "exit code -9" in publisher.error


def test_after_a_step_the_publisher_could_not_take_the_whole_state_goes(exercise):
    """Steps carry only the floes that changed, so steps lost in the handover (the publisher
    process stopped) would leave its view, and every late joiner's, behind for good: the
    step after the loss sends the whole state instead."""
    _, cfg, model = exercise
    data = start_world(model, cfg)
    with StatePublisher(cfg.stream) as publisher:
        stream = StreamOutput(publisher, None, model.origin, lambda: snapshot(model, data))
        publisher.publish(snapshot(model, data))

        def tick() -> None:
            stream.on_step(TickOutcome(step(model, data, 0.1), Controls(), (), time.monotonic(), None))
        os.kill(publisher._process.pid, signal.SIGSTOP)
        try:
            while publisher.dropped < 50 and data.seq < 20000:  # floes break and come to rest, unheard
                tick()
        finally:
            os.kill(publisher._process.pid, signal.SIGCONT)
        assert publisher.dropped >= 50
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline:  # the publisher catches up; the first step it takes is the whole state
            dropped = publisher.dropped
            tick()
            if publisher.dropped == dropped:
                break
            time.sleep(0.05)
        with StateSubscriber(cfg.stream.publish, cfg.stream.snapshot) as late:
            late.sync()
            deadline = time.monotonic() + 20.0
            while late.view.seq < data.seq and time.monotonic() < deadline:
                late.poll(50)
            truth = WorldView()
            truth.apply(decode(encode(snapshot(model, data)))[0])
            views_equal(late.view, truth)


def test_a_dis_vessel_goes_out_as_ais_and_reaches_a_late_joiners_traffic(exercise):
    """Another simulator's Entity State PDU (opendis) becomes a vessel: !AIVDM on the NMEA
    link, and a row of WorldView.traffic for a subscriber that joins after it was heard."""
    _, cfg, model = exercise
    data = start_world(model, cfg)
    nmea_rx, listen, sim = receiver(), free_port(), socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    links = node_config([{"type": "dis", "name": "dis", "listen_port": listen,
                          "send_to": [f"127.0.0.1:{free_port()}"]},
                         {"type": "nmea0183", "name": "plotter", "udp_port": nmea_rx.getsockname()[1],
                          "rates": dict.fromkeys(QUIET, 0), "ais": {"mmsi": 257123450, "to_bow": 20,
                                                                    "to_stern": 130, "to_port": 10,
                                                                    "to_starboard": 12}}]).links

    def tick() -> None:
        now = time.monotonic()
        hub.poll(now)
        events = step(model, data, 0.1)
        hub.publish(events.ship, now)
        publisher.publish(events, traffic=hub.traffic.table(model.origin))

    with LinkHub(links, cfg.arbitration) as hub, StatePublisher(cfg.stream) as publisher:
        wait_for(lambda: hub.links[0].connected, poll=tick)
        sim.sendto(other_simulator_pdu(74.002, 20.003, math.radians(250.0), 6.0), ("127.0.0.1", listen))
        wait_for(lambda: hub.traffic.current, poll=tick)
        [vessel] = hub.traffic.current
        with StateSubscriber(cfg.stream.publish, cfg.stream.snapshot) as late:
            late.sync()
            [row] = late.view.traffic
            tick()
            late.poll(1000)
            assert late.view.traffic.dtype == TRAFFIC_DTYPE and len(late.view.traffic) == 1
    sim.close()
    vdm = [ais_decode(d.decode().strip()).asdict() for d in datagrams(nmea_rx) if d.startswith(b"!AIVDM,1,")]
    nmea_rx.close()
    assert {m["mmsi"] for m in vdm if m["msg_type"] == 1} == {vessel.mmsi}  # one report per 10 s while it lasts
    assert vdm[0]["lat"] == pytest.approx(74.002, abs=1e-4 / 60) and vdm[0]["speed"] == pytest.approx(11.7, abs=0.1)
    north, east = geodetic_to_local(math.radians(74.002), math.radians(20.003), *model.origin)
    assert row["id"] == vessel.mmsi and (row["x"], row["y"]) == pytest.approx((east, north), abs=0.5)
    assert row["heading"] == pytest.approx(math.radians(250.0), abs=1e-3)  # true, clockwise from north
    assert row["speed"] == pytest.approx(6.0, abs=1e-3) and (row["length"], row["beam"]) == (0.0, 0.0)


def render_node(config, out, *args) -> subprocess.Popen:
    """A render process that ends by itself 3 s after the physics stops stepping."""
    return subprocess.Popen([sys.executable, "-m", "bridge_node", "render-node", "--config", str(config),
                             "--fps", "10", "--idle-exit", "3", "--out", str(out), *args], cwd=REPO,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def test_render_processes_draw_what_one_process_draws(exercise, tmp_path):
    """Physics here; two render processes, each with one channel, join mid-exercise (one
    losing every 5th message); once the physics stops they show exactly the final state."""
    path, cfg, model = exercise
    data = start_world(model, cfg)
    with StatePublisher(cfg.stream) as publisher:
        for _ in range(300):
            publisher.publish(step(model, data, 0.1))
        nodes = [render_node(path, tmp_path, "--channels", "bow", "--panorama", str(tmp_path / "bow.png"),
                             "--summary", str(tmp_path / "bow.json")),
                 render_node(path, tmp_path, "--channels", "aft", "--panorama", str(tmp_path / "aft.png"),
                             "--summary", str(tmp_path / "aft.json"), "--drop-every", "5")]
        deadline = time.monotonic() + 120.0
        while publisher.snapshots < 2 and time.monotonic() < deadline:
            assert all(n.poll() is None for n in nodes), [n.communicate() for n in nodes]
            publisher.publish(step(model, data, 0.1))
            time.sleep(0.1)
        for _ in range(60):  # the exercise goes on while they draw
            publisher.publish(step(model, data, 0.1))
            time.sleep(0.05)
        for n in nodes:  # physics stopped: they settle on the last state and end by themselves
            assert n.wait(120) == 0, n.stderr.read()
    summaries = {name: json.loads((tmp_path / f"{name}.json").read_text()) for name in ("bow", "aft")}
    assert all(s["last_seq"] == data.seq for s in summaries.values())
    assert summaries["aft"]["resyncs"] > 0  # it lost messages, and took snapshots instead
    view = WorldView()
    view.apply(decode(encode(snapshot(model, data)))[0])
    cs = ChannelSet(SceneRenderer(create_context(), model, cfg.render), cfg.render.channels)
    cs.render(view)
    for target in cs.targets:
        remote = np.asarray(Image.open(tmp_path / f"{target.channel.name}.png")).astype(int)
        local = target.image().astype(int)
        assert np.abs(remote - local).max() <= 3, target.channel.name
        assert local.std() > 10


def test_a_slow_renderer_never_holds_the_physics_back(exercise, tmp_path):
    path, cfg, model = exercise
    data = start_world(model, cfg)
    seqs = []
    with StatePublisher(cfg.stream) as publisher, LinkHub([], cfg.arbitration) as hub:
        publisher.publish(snapshot(model, data))
        slow = render_node(path, tmp_path, "--channels", "bow", "--frame-delay", "0.5",
                           "--summary", str(tmp_path / "slow.json"))
        deadline = time.monotonic() + 120.0
        while publisher.snapshots < 1 and time.monotonic() < deadline:
            assert slow.poll() is None, slow.communicate()
            time.sleep(0.1)

        def on_step(outcome):
            seqs.append(outcome.events.seq)
            publisher.publish(outcome.events, outcome.input_time)
        stats = run_realtime(model, data, hub, 30.0, 3.0, [on_step])
        assert slow.wait(120) == 0, slow.stderr.read()
    summary = json.loads((tmp_path / "slow.json").read_text())
    assert seqs == list(range(1, stats.ticks + 1))  # no step skipped
    assert stats.sim_s == pytest.approx(stats.ticks / 30.0)
    assert publisher.sent == stats.ticks + 1 and publisher.dropped == 0
    assert summary["frames"] < stats.ticks / 4  # the renderer drew far fewer frames than steps...
    assert summary["last_seq"] == data.seq  # ...yet it caught up with the last one


def test_a_render_process_that_dies_is_restarted(exercise, tmp_path):
    path, cfg, model = exercise
    data = start_world(model, cfg)
    with StatePublisher(cfg.stream) as publisher:
        publisher.publish(snapshot(model, data))
        renderers = RenderProcesses(cfg, str(path), tmp_path, None)
        renderers.start()
        first = renderers.processes[0].proc
        first.kill()
        first.wait(30)
        renderers.check()  # notices the death and starts it again; never waits for it
        second = renderers.processes[0].proc
        assert second is not first and second.poll() is None
        deadline = time.monotonic() + 120.0
        while publisher.snapshots < 1 and time.monotonic() < deadline:  # the new one joins
            renderers.check()
            publisher.publish(step(model, data, 0.1))
            time.sleep(0.1)
        summary, = renderers.stop()
    assert summary["restarts"] == 1 and summary["exit"] == 0 and summary["last_seq"] == data.seq
    assert summary["errors"][0].startswith("exit -9")
    assert (tmp_path / "video.mp4").exists() and (tmp_path / "panorama.png").exists()
