"""Who may open the station's page and WebSocket: an ASGI wrapper in front of the app.

On loopback (the default) only a loopback Host header is served (a web page elsewhere
cannot reach the station by DNS rebinding), and a WebSocket whose Origin is another site is
refused. With a token (always when the network is opened), every request must carry it (the
``icebridge_token`` cookie the login page sets, ``?token=``, or ``Authorization: Bearer``):
a page request without it gets 401 and the login form, anything else 401, and a WebSocket
is closed before it opens (the browser sees HTTP 403)."""
from __future__ import annotations

import hmac
import html
from http.cookies import CookieError, SimpleCookie
from urllib.parse import parse_qs, unquote, urlsplit

from starlette.datastructures import Headers
from starlette.types import ASGIApp, Receive, Scope, Send

from bridge_node.common.network import is_loopback_host

COOKIE = "icebridge_token"
LOGIN_PAGE = """<!doctype html><html lang="en"><head><meta charset="utf-8"><title>IceBridge instructor: sign in</title>
<style>body{background:#0e1a24;color:#d8e4ec;font:15px system-ui,sans-serif;display:flex;height:100vh;margin:0;
align-items:center;justify-content:center}form{background:#162634;padding:28px 32px;border-radius:8px;width:340px}
h1{font-size:18px;margin:0 0 14px}input{width:100%;box-sizing:border-box;padding:8px;margin:8px 0 14px;
background:#0e1a24;color:#fff;border:1px solid #3b5569;border-radius:4px}button{padding:8px 18px;background:#2f7fc1;
color:#fff;border:0;border-radius:4px;cursor:pointer}p{color:#f08a7e;min-height:1em;margin:0 0 8px}</style></head>
<body><form id="f"><h1>IceBridge instructor station</h1><p>{message}</p><label>Access token (the node's control token)
<input id="t" type="password" autocomplete="current-password" autofocus></label><button>Sign in</button></form>
<script>document.getElementById('f').onsubmit=function(e){e.preventDefault();
document.cookie='icebridge_token='+encodeURIComponent(document.getElementById('t').value)+';path=/;SameSite=Strict';
location.reload();};</script></body></html>"""


def _host_name(host_header: str) -> str:
    """The host of a Host header (``[::1]:8470``, ``127.0.0.1:8470``, ``localhost``)."""
    return urlsplit(f"//{host_header}").hostname or ""


class TokenGate:
    """Serve ``app`` only to requests with the token (None: no token asked) and, on
    loopback, only to loopback Host headers and same-origin WebSockets."""

    def __init__(self, app: ASGIApp, token: str | None, loopback_only: bool) -> None:
        self.app, self.token, self.loopback_only = app, token, loopback_only

    def _token_of(self, scope: Scope, headers: Headers) -> str | None:
        cookie = SimpleCookie()
        try:
            cookie.load(headers.get("cookie", ""))
        except CookieError:  # a malformed cookie header counts as none
            cookie = SimpleCookie()
        if COOKIE in cookie:
            return unquote(cookie[COOKIE].value)
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        if "token" in query:
            return query["token"][0]
        auth = headers.get("authorization", "")
        return auth[7:] if auth.startswith("Bearer ") else None

    def refusal(self, scope: Scope) -> tuple[int, str] | None:
        """Why a request is refused (HTTP status, text), or None."""
        headers = Headers(scope=scope)
        host = _host_name(headers.get("host", ""))
        if self.loopback_only:
            try:
                local = is_loopback_host(host)
            except ValueError:
                local = False
            if not local:
                return 421, f"host {host!r}: this station serves loopback addresses only"
        origin = headers.get("origin")
        if scope["type"] == "websocket" and origin and urlsplit(origin).netloc != headers.get("host"):
            return 403, "a WebSocket from another site"
        if self.token is not None:
            given = self._token_of(scope, headers)
            if not (given and hmac.compare_digest(given.encode(), self.token.encode())):
                return 401, "the access token was not accepted" if given else ""
        return None

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        refused = self.refusal(scope)
        if refused is None:
            await self.app(scope, receive, send)
        elif scope["type"] == "websocket":
            await receive()  # websocket.connect
            await send({"type": "websocket.close", "code": 1008, "reason": refused[1] or "access token needed"})
        else:
            status, text = refused
            page = scope["path"] in ("/", "/index.html") and status == 401
            body = (LOGIN_PAGE.replace("{message}", html.escape(text)) if page else text or "access token needed").encode()
            await send({"type": "http.response.start", "status": status, "headers": [
                (b"content-type", b"text/html; charset=utf-8" if page else b"text/plain; charset=utf-8"),
                (b"content-length", str(len(body)).encode()), (b"cache-control", b"no-store")]})
            await send({"type": "http.response.body", "body": body})
