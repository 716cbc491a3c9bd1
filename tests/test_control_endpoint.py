"""The node's control endpoint on the loopback, with real ZeroMQ clients: commands checked and
queued, every bad message refused with a clear reply and counted, a flood answered without
growing the queue, and the access token asked for where one is set."""
import json
import threading

import pytest
import zmq
from pydantic import ValidationError

from bridge_node.control.client import request
from bridge_node.control.endpoint import REFUSALS_PER_SECOND, ControlEndpoint
from bridge_node.control.queue import CommandQueue
from bridge_node.control.settings import ControlSettings
from bridge_node.common.errors import UserError
from bridge_node.common.network import free_port

TOKEN = "a-long-enough-token-0123"


def endpoint(**settings) -> tuple[ControlEndpoint, CommandQueue, str]:
    s = ControlSettings(endpoint=f"tcp://127.0.0.1:{free_port()}", **settings)
    queue = CommandQueue(s.queue, s.per_tick)
    return ControlEndpoint(s, queue, lambda: {"time_s": 12.5}), queue, s.endpoint


def test_commands_are_queued_and_bad_ones_refused_with_the_reason():
    ep, queue, address = endpoint()
    with ep:
        assert request(address, {"command": {"command": "freeze"}}, None) == {"ok": True, "queued": "freeze"}
        assert request(address, {"request": "status"}, None) == {"ok": True, "status": {"time_s": 12.5}}
        bad = request(address, {"command": {"command": "wind", "speed_kn": float("inf"), "from_deg": 1.0}}, None)
        assert not bad["ok"] and "speed_kn = Infinity" in bad["error"] and "finite" in bad["error"]
        unknown = request(address, {"command": {"command": "sink"}}, None)
        assert not unknown["ok"] and "'sink': unknown" in unknown["error"]
        with zmq.Context.instance().socket(zmq.REQ) as raw:
            raw.setsockopt(zmq.RCVTIMEO, 5000)
            raw.connect(address)
            for payload, word in ((b"{not json", "not a JSON object"), (b"[1]", "not a JSON object"),
                                  (b"[" * 5000 + b"]" * 5000, "bytes; at most"),
                                  (json.dumps({"command": {"command": "freeze", "x": "y" * 5000}}).encode(),
                                   "bytes; at most")):
                raw.send(payload)
                reply = json.loads(raw.recv())
                assert not reply["ok"] and word in reply["error"]
        with zmq.Context.instance().socket(zmq.REQ) as huge:  # over ZeroMQ's own limit: dropped unread
            huge.setsockopt(zmq.RCVTIMEO, 1000)
            huge.connect(address)
            huge.send(b"x" * 200_000)
            with pytest.raises(zmq.Again):
                huge.recv()
        assert request(address, {"request": "status"}, None)["ok"]  # and the endpoint serves on
    assert len(queue._waiting) == 1  # only the good command
    assert dict(ep.counts) == {"accepted": 1, "status": 2, "invalid": 2, "malformed": 2, "oversized": 2}


def test_a_flood_gets_clean_replies_and_never_grows_the_queue():
    ep, queue, address = endpoint(per_second=50, queue=8)
    replies = []
    with ep:
        context = zmq.Context.instance()
        sock = context.socket(zmq.DEALER)  # many requests in flight, as a flooding client sends them
        sock.setsockopt(zmq.RCVTIMEO, 10_000)
        sock.setsockopt(zmq.LINGER, 0)
        sock.connect(address)
        message = json.dumps({"command": {"command": "visibility", "visibility_m": 500.0}}).encode()
        for _ in range(10_000):
            sock.send_multipart([b"", message])
        try:
            while len(replies) < 10_000:
                replies.append(json.loads(sock.recv_multipart()[-1]))
        except zmq.Again:
            pass
        sock.close()
        alive = ep._thread.is_alive()
    assert alive and len(replies) >= 50 + REFUSALS_PER_SECOND  # every message read got a clean reply
    assert all(set(r) <= {"ok", "queued", "error"} for r in replies)
    assert sum(r["ok"] for r in replies) == len(queue._waiting) == 8  # the queue's bound held
    assert {r["error"].split(":")[0] for r in replies if not r["ok"]} == {"flooding", "8 commands already wait for "
                                                                           "the physics; refused"}
    assert ep.counts["flooding"] + ep.counts["busy"] + ep.counts["accepted"] == len(replies)


def test_with_a_token_a_client_without_it_can_neither_watch_nor_command():
    ep, queue, address = endpoint(token=TOKEN)
    with ep:
        for token in (None, "wrong-token-wrong-token"):
            for message in ({"request": "status"}, {"command": {"command": "freeze"}}):
                reply = request(address, message, token)
                assert reply == {"ok": False, "error": "access token missing or wrong"}
        assert request(address, {"request": "status"}, TOKEN)["ok"]
    assert len(queue._waiting) == 0 and ep.counts["unauthorised"] == 4


def test_the_network_is_opened_only_with_allow_network_and_a_token(monkeypatch):
    with pytest.raises(ValidationError, match="not a loopback address; set allow_network"):
        ControlSettings(endpoint="tcp://192.168.1.20:5562")
    monkeypatch.delenv("ICEBRIDGE_TOKEN", raising=False)
    with pytest.raises(UserError, match="needs an access token"):
        ControlEndpoint(ControlSettings(endpoint="tcp://0.0.0.0:5599", allow_network=True), CommandQueue(), dict)
    monkeypatch.setenv("ICEBRIDGE_TOKEN", TOKEN)
    assert ControlSettings(endpoint="tcp://0.0.0.0:5599", allow_network=True).access_token() == TOKEN


def test_a_client_gets_a_clear_error_when_no_node_answers():
    with pytest.raises(UserError, match="no node answered at tcp://127.0.0.1:.* within 0.3 s"):
        request(f"tcp://127.0.0.1:{free_port()}", {"request": "status"}, None, 0.3)


def test_stopping_twice_is_safe_and_frees_the_port():
    ep, _, address = endpoint()
    with ep:
        pass
    ep.stop()
    again = ControlEndpoint(ep.settings, CommandQueue(), dict)  # the port is free again
    again.stop()
    assert threading.active_count() >= 1
