"""Where the state stream is served (``[stream]`` in the config)."""
from __future__ import annotations

from pydantic import Field, model_validator

from bridge_node.common.network import endpoint_host, loopback_unless
from sim_core.params import Params


class StreamSettings(Params):
    """The physics process publishes each step on ``publish`` and answers snapshot requests
    on ``snapshot``; render processes connect to both. Loopback unless ``allow_network``."""

    publish: str = Field("tcp://127.0.0.1:5560", description="PUB endpoint of the step stream")
    snapshot: str = Field("tcp://127.0.0.1:5561", description="ROUTER endpoint of the snapshot service")
    allow_network: bool = False
    send_hwm: int = Field(50, ge=1, le=100_000, description="messages queued per subscriber before it is dropped")

    @model_validator(mode="after")
    def _endpoints(self) -> "StreamSettings":
        for key in ("publish", "snapshot"):
            loopback_unless(endpoint_host(getattr(self, key), key), self.allow_network, key)
        if self.publish == self.snapshot:
            raise ValueError("publish and snapshot must be different endpoints")
        return self
