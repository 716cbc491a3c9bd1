"""A client of the node's control endpoint: one request, one reply (ZeroMQ REQ)."""
from __future__ import annotations

import json

import zmq

from bridge_node.common.errors import UserError


def request(endpoint: str, message: dict, token: str | None, timeout_s: float = 5.0) -> dict:
    """Send one request (the token added) and return the node's reply; UserError where no
    node answers within ``timeout_s`` or the reply is no JSON object."""
    context = zmq.Context.instance()
    sock = context.socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.RCVTIMEO, max(1, int(timeout_s * 1000)))
    try:
        sock.connect(endpoint)
        sock.send(json.dumps({**message, **({"token": token} if token else {})}).encode())
        try:
            reply = json.loads(sock.recv())
        except zmq.Again:
            raise UserError(f"no node answered at {endpoint} within {timeout_s:g} s (is icebridge run going, "
                            "and is this its control.endpoint?)") from None
        except ValueError:
            raise UserError(f"{endpoint} answered with something that is not JSON") from None
    except zmq.ZMQError as exc:
        raise UserError(f"{endpoint}: {exc}") from None
    finally:
        sock.close()
    if not isinstance(reply, dict):
        raise UserError(f"{endpoint} answered with something that is not a JSON object")
    return reply
