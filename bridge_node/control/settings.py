"""Where the control endpoint listens (``[control]`` in the config), and who may use it."""
from __future__ import annotations

import os

from pydantic import Field, model_validator

from bridge_node.common.network import endpoint_host, loopback_unless
from sim_core.params import Params

TOKEN_VARIABLE = "ICEBRIDGE_TOKEN"  # the access token, where the config does not hold it


class ControlSettings(Params):
    """The node's control endpoint: a ZeroMQ ROUTER the instructor station and ``icebridge
    ctl`` send commands to. Loopback unless ``allow_network``; opened to a network, it asks
    for an access token (``token``, or the ``ICEBRIDGE_TOKEN`` environment variable) before
    it answers anything. A token given on loopback is asked for there too."""

    endpoint: str = Field("tcp://127.0.0.1:5562", description="ROUTER endpoint of the instructor's commands")
    allow_network: bool = False
    token: str | None = Field(None, min_length=16, max_length=256, description="access token (16+ characters)")
    queue: int = Field(64, ge=1, le=10_000, description="commands waiting for a tick, at most")
    per_tick: int = Field(4, ge=1, le=100, description="commands a tick applies, at most")
    per_second: int = Field(50, ge=1, le=10_000, description="messages taken a second, at most; more are refused")

    @model_validator(mode="after")
    def _where(self) -> ControlSettings:
        loopback_unless(endpoint_host(self.endpoint, "endpoint"), self.allow_network, "endpoint")
        return self

    def access_token(self) -> str | None:
        """The token clients must give: the config's, else the environment's, else None."""
        return self.token or os.environ.get(TOKEN_VARIABLE) or None
