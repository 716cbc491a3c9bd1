"""Which addresses the node may use: loopback unless the config explicitly allows a network."""
from __future__ import annotations

import ipaddress


def loopback_unless(host: str, allowed: bool, key: str) -> str:
    """The host if it is a loopback IP address, or any IP address when ``allowed``;
    ValueError (naming the config key) otherwise."""
    try:
        ip = ipaddress.ip_address(host)
    except ValueError:
        raise ValueError(f"{key} must be an IP address, got {host!r}") from None
    if not ip.is_loopback and not allowed:
        raise ValueError(f"{key} = {host!r} is not a loopback address; set allow_network = true to use a network")
    return host
