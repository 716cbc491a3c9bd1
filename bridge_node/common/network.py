"""Which addresses the node may use: loopback unless the config explicitly allows a network."""
from __future__ import annotations

import ipaddress
import re
import socket
from urllib.parse import urlsplit

# pyserial URLs that open a network connection (socket://HOST:PORT, rfc2217://HOST:PORT),
# also inside another URL (spy://, for one)
_SERIAL_NETWORK_URL = re.compile(r"(?:socket|rfc2217)://(?:\[([^\]]*)\]|([^/:?]*))", re.IGNORECASE)
# python-can interfaces that reach a network
NETWORK_CAN_INTERFACES = ("udp_multicast", "socketcand")
_HANDED_OUT: set[int] = set()  # ports free_port has returned in this process


def is_loopback_host(host: str) -> bool:
    """True for ``localhost`` and loopback IP addresses (ValueError for other names)."""
    return host == "localhost" or ipaddress.ip_address(host).is_loopback


def loopback_unless(host: str, allowed: bool, key: str) -> str:
    """The host if it is a loopback IP address (or ``localhost``), or any IP address when
    ``allowed``; ValueError (naming the config key) otherwise."""
    try:
        loopback = is_loopback_host(host)
    except ValueError:
        raise ValueError(f"{key} must be an IP address, got {host!r}") from None
    if not loopback and not allowed:
        raise ValueError(f"{key} = {host!r} is not a loopback address; set allow_network = true to use a network")
    return host


def serial_port_unless(port: str, allowed: bool, key: str) -> str:
    """A serial port or pyserial URL; a URL that opens a network connection must name a
    loopback host unless ``allowed``."""
    for bracketed, plain in _SERIAL_NETWORK_URL.findall(port):
        loopback_unless(bracketed or plain, allowed, key)
    return port


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on now and that this process has not
    handed out before: nothing holds a port between this call and its user's bind, so two
    calls could otherwise return the same one. Another process may still take it first."""
    while True:
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        if port not in _HANDED_OUT:
            _HANDED_OUT.add(port)
            return port


def endpoint_host(endpoint: str, key: str) -> str:
    """The host of a ``tcp://HOST:PORT`` endpoint; ValueError naming the key otherwise."""
    parts = urlsplit(endpoint)
    try:
        port = parts.port
    except ValueError:
        port = None
    if parts.scheme != "tcp" or not parts.hostname or port is None:
        raise ValueError(f"{key} = {endpoint!r}: expected tcp://HOST:PORT")
    return parts.hostname
