"""Who may use the web app: the access token and the Host check, as ASGI middleware.

Rules (issue 18, security):

1. Without a token (the default) the app serves loopback only (``ground.web.server``), and
   every request and WebSocket must name a loopback host in ``Host`` (``127.0.0.1``,
   ``localhost``, ``[::1]``, any port): a page of another site whose name an attacker
   points at 127.0.0.1 (DNS rebinding) would otherwise be this server's own origin.
2. With a token (any other address to serve on requires one), every request and WebSocket
   carries it: the cookie :data:`COOKIE` (``HttpOnly``, ``SameSite=Strict``, so another
   site's page never sends it), or ``Authorization: Bearer TOKEN`` for scripts. The URL
   printed at start has ``?token=TOKEN``: a GET with the right one sets the cookie and
   redirects to the same path without it (the token leaves the address bar and the
   history). Tokens are compared in constant time.
3. Refused: HTTP 401 (403 for a wrong Host), JSON ``{"error": "one line"}``; a WebSocket
   is closed before it opens (the client sees HTTP 403). Commands also need the page's
   own origin (``ground.web.app.same_origin``), checked by the routes.
4. The MAVLink signing key is not the token and never leaves the station: nothing served
   is derived from it.
"""

from __future__ import annotations

import hmac
import http.cookies
import json
import logging
import re
import secrets
import urllib.parse
from pathlib import Path
from typing import Any

from shared.errors import InputError
from shared.guarded_http import host_name_of, is_loopback_name

_log = logging.getLogger(__name__)

Scope = dict[str, Any]
#: The cookie that carries the token (rule 2).
COOKIE = "vmnav_token"
#: Characters of a token read from a file, at least.
MIN_TOKEN_CHARS = 16
#: What a token read from a file may be made of (what a URL and a cookie carry as is).
TOKEN_FORM = re.compile(rf"[A-Za-z0-9._~-]{{{MIN_TOKEN_CHARS},}}")
#: Bytes of randomness of a generated token (32 characters of base64url).
TOKEN_BYTES = 24


def generate_token() -> str:
    """A fresh random token, URL-safe."""
    return secrets.token_urlsafe(TOKEN_BYTES)


def read_token_file(path: Path) -> str:
    """The token in ``path``: its first line, stripped.

    Raises:
        InputError: the file cannot be read, or the token is shorter than
            :data:`MIN_TOKEN_CHARS` or not printable ASCII without spaces.
    """
    try:
        text = path.read_text(encoding="ascii")
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(str(path), f"cannot read the token: {getattr(e, 'strerror', None) or e}"
                         ) from None
    lines = text.strip().splitlines()
    token = lines[0].strip() if lines else ""
    if not TOKEN_FORM.fullmatch(token):
        raise InputError(str(path), f"the token must be at least {MIN_TOKEN_CHARS} characters "
                                    "of letters, digits and -._~ (no spaces)")
    return token


def is_loopback_host(host: str) -> bool:
    """Whether ``host`` (a ``Host`` header: name or address, maybe ``:port``) is loopback."""
    return is_loopback_name(host_name_of(host))


def _headers(scope: Scope) -> dict[str, str]:
    return {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}


def _cookie(headers: dict[str, str]) -> str | None:
    jar = http.cookies.SimpleCookie()
    try:
        jar.load(headers.get("cookie", ""))
    except http.cookies.CookieError:
        return None
    morsel = jar.get(COOKIE)
    return morsel.value if morsel is not None else None


class AccessGate:
    """The ASGI app ``app`` behind rules 1-3.

    Args:
        app: the web app.
        token: the token every request must carry; None to serve loopback hosts only.
    """

    def __init__(self, app: Any, token: str | None) -> None:
        self.app = app
        self.token = token

    def _valid(self, candidate: str | None) -> bool:
        assert self.token is not None
        return candidate is not None and hmac.compare_digest(
            candidate.encode("utf-8", "replace"), self.token.encode())

    async def __call__(self, scope: Scope, receive: Any, send: Any) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = _headers(scope)
        if self.token is None:
            if not is_loopback_host(headers.get("host", "")):
                await self._refuse(scope, receive, send, 403,
                                   f"Host {headers.get('host')!r:.60} is not this machine "
                                   "(without a token the app serves loopback names only)")
                return
            await self.app(scope, receive, send)
            return
        query = urllib.parse.parse_qs(scope.get("query_string", b"").decode("latin-1"))
        in_query = query.get("token", [None])[0]
        if scope["type"] == "http" and scope["method"] == "GET" and self._valid(in_query):
            await self._enter(scope, send, query)
            return
        bearer = headers.get("authorization", "")
        if self._valid(_cookie(headers)) or (
                bearer.startswith("Bearer ") and self._valid(bearer[7:].strip())):
            await self.app(scope, receive, send)
            return
        await self._refuse(scope, receive, send, 401, "no valid access token (open the URL "
                                             "`vmnav ground web` printed, with its ?token=)")

    async def _enter(self, scope: Scope, send: Any, query: dict[str, list[str]]) -> None:
        """Set the cookie and redirect to the same path without the token (rule 2)."""
        assert self.token is not None
        rest = urllib.parse.urlencode({k: v for k, v in query.items() if k != "token"},
                                      doseq=True)
        # One leading slash: "//host/..." would send the browser to another site.
        location = "/" + urllib.parse.quote(scope["path"]).lstrip("/") + (
            f"?{rest}" if rest else "")
        cookie = f"{COOKIE}={self.token}; Path=/; HttpOnly; SameSite=Strict"
        await send({"type": "http.response.start", "status": 303, "headers": [
            (b"location", location.encode("latin-1")), (b"set-cookie", cookie.encode()),
            (b"cache-control", b"no-store"), (b"content-length", b"0")]})
        await send({"type": "http.response.body", "body": b""})

    async def _refuse(self, scope: Scope, receive: Any, send: Any, status: int,
                      why: str) -> None:
        client = scope.get("client")
        _log.warning("%s %s from %s refused: %s", scope["type"], scope["path"],
                     client[0] if client else "?", why)
        if scope["type"] == "websocket":
            await receive()  # websocket.connect; closing now refuses it (HTTP 403)
            await send({"type": "websocket.close", "code": 1008})
            return
        body = json.dumps({"error": why}).encode()
        await send({"type": "http.response.start", "status": status, "headers": [
            (b"content-type", b"application/json"),
            (b"content-length", str(len(body)).encode())]})
        await send({"type": "http.response.body", "body": body})
