"""Where the instructor station serves its page (``[instructor]`` in the config), and who
may use it."""
from __future__ import annotations

from pydantic import Field, model_validator

from bridge_node.common.network import loopback_unless
from sim_core.params import Params


class InstructorSettings(Params):
    """The instructor station's web server (``icebridge instructor``). Loopback unless
    ``allow_network``; opened to a network, the page and its WebSocket ask for the control
    endpoint's access token (``control.token`` or ``ICEBRIDGE_TOKEN``) before they show or
    command anything. A token given on loopback is asked for there too, as the control
    endpoint does."""

    host: str = Field("127.0.0.1", description="address the web server listens on")
    port: int = Field(8470, ge=1, le=65535, description="TCP port of the web page and its WebSocket")
    allow_network: bool = False
    rate_hz: float = Field(10.0, ge=1.0, le=30.0, description="map updates a second sent to each browser")
    start: bool = Field(False, description="icebridge run starts the station beside the node")
    niceness: int = Field(10, ge=0, le=19, description="scheduling niceness of the station's process: the "
                          "physics loop comes first for the CPU")

    @model_validator(mode="after")
    def _where(self) -> InstructorSettings:
        loopback_unless(self.host, self.allow_network, "host")
        return self
