"""Who may use the dashboard: the token, the host names it answers to, the origins it accepts.

Every request (pages, assets, the websocket) needs the token, even on loopback: any local user can
reach a loopback port. The ``Host`` header must name this dashboard (``localhost``, ``127.0.0.1``,
``[::1]``, the address it listens on, or a name given with ``--allow-host``), so a page on another
site whose name an attacker points at 127.0.0.1 (DNS rebinding) is refused; and a request or
websocket that carries an ``Origin`` must come from the page's own origin.
"""
from __future__ import annotations

import contextlib
import ipaddress
import os
import re
import secrets
import socket
from http.cookies import SimpleCookie
from typing import Any, Awaitable, Callable, Iterable, MutableMapping, Optional, Set, Tuple
from urllib.parse import parse_qs, urlsplit

__all__ = ["Gate", "TokenGate", "load_token", "served_names", "TOKEN_COOKIE", "TOKEN_ENV"]

TOKEN_COOKIE = "hubwire_token"
#: where a token may come from without appearing in the process list
TOKEN_ENV = "HUBWIRE_DASHBOARD_TOKEN"

Scope = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[MutableMapping[str, Any]]]
Send = Callable[[MutableMapping[str, Any]], Awaitable[None]]

_WILDCARDS = ("", "0.0.0.0", "::")
_TOKEN = re.compile(r"[A-Za-z0-9._~-]{1,256}\Z")


def load_token(token: Optional[str] = None, token_file: Optional[str] = None) -> Tuple[str, bool]:
    """``(token, made)``: the first line of ``token_file``, else ``token``, else $HUBWIRE_DASHBOARD_TOKEN,
    else a new random one (``made``: only that one may be printed)."""
    given = token
    if token_file:
        with open(token_file, encoding="utf-8") as f:
            given = f.readline().strip()
        if not given:
            raise ValueError(f"{token_file} holds no token (its first line is empty)")
    given = given or os.environ.get(TOKEN_ENV, "").strip()
    if not given:
        return secrets.token_urlsafe(24), True
    if not _TOKEN.match(given):
        raise ValueError("a dashboard token is letters, digits and - _ . ~ only (it travels in URLs and a cookie)")
    return given, False


def served_names(bind: str, extra: Iterable[str] = ()) -> Set[str]:
    """Host names (lower case, IPv6 without brackets) the dashboard answers to when it listens on
    ``bind``; listening on every address also answers to this machine's name."""
    names = {"localhost", "127.0.0.1", "::1"} | {e.strip().lower().strip("[]") for e in extra if e.strip()}
    if bind in _WILDCARDS:
        names.add(socket.gethostname().lower())
    else:
        names.add(bind.lower().strip("[]"))
    return names


def _host_name(value: str) -> Optional[str]:
    """The name in a ``Host`` value or an origin's netloc (``[::1]:8080`` -> ``::1``), or None."""
    value = value.strip().lower()
    if not value:
        return None
    if value.startswith("["):
        end = value.find("]")
        rest = value[end + 1:]
        if end < 2 or (rest and not (rest[:1] == ":" and rest[1:].isdigit())):
            return None
        return value[1:end]
    name, _, port = value.partition(":")
    return name if name and (not port or port.isdigit()) else None


def _is_ip(name: str) -> bool:
    try:
        ipaddress.ip_address(name)
        return True
    except ValueError:
        return False


class Gate:
    """ASGI middleware in front of the whole app (NiceGUI's pages, assets and socket.io):
    a known ``Host``, a same-origin ``Origin`` (when one is sent), then the token, given once as
    ``?token=...`` (then kept in a cookie for this site) or as the cookie itself."""

    def __init__(self, app: Any, token: str, names: Optional[Set[str]] = None, any_ip: bool = False) -> None:
        self.app = app
        self.token = token
        self.names = names if names is not None else served_names("127.0.0.1")
        #: listening on every address: an IP literal names this machine (no DNS, so no rebinding)
        self.any_ip = any_ip

    def _header(self, scope: Scope, key: bytes) -> Optional[str]:
        for name, value in scope.get("headers", []):
            if name == key:
                return str(value.decode("latin-1"))
        return None

    def _known(self, name: Optional[str]) -> bool:
        return name is not None and (name in self.names or (self.any_ip and _is_ip(name)))

    def _why_not(self, scope: Scope) -> Optional[Tuple[int, str]]:
        host = self._header(scope, b"host")
        if host is None or not self._known(_host_name(host)):
            return 400, (f"unknown host name {host!r}: this dashboard answers to {', '.join(sorted(self.names))} "
                         "(start it with --allow-host NAME for another)")
        origin = self._header(scope, b"origin")
        if origin is not None:
            o = urlsplit(origin)
            if o.scheme not in ("http", "https") or o.netloc.lower() != host.strip().lower():
                return 403, f"requests from pages of {origin!r} are not accepted"
        if not self._token_ok(scope):
            return 401, "open the address printed at start (with ?token=...)"
        return None

    def _token_ok(self, scope: Scope) -> bool:
        q = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token", [])
        if any(secrets.compare_digest(t.encode(), self.token.encode()) for t in q):
            return True
        cookie = self._header(scope, b"cookie")
        if cookie is not None:
            c: SimpleCookie = SimpleCookie()
            with contextlib.suppress(Exception):
                c.load(cookie)
            if TOKEN_COOKIE in c and secrets.compare_digest(c[TOKEN_COOKIE].value.encode(), self.token.encode()):
                return True
        return False

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        refused = self._why_not(scope)
        if refused is None:
            if scope["type"] == "http" and b"token=" in scope.get("query_string", b""):
                send = self._with_cookie(send)
            await self.app(scope, receive, send)
            return
        if scope["type"] == "websocket":
            await send({"type": "websocket.close", "code": 1008})
            return
        body = f"hubwire dashboard: {refused[1]}\n".encode()
        await send({"type": "http.response.start", "status": refused[0],
                    "headers": [(b"content-type", b"text/plain; charset=utf-8"),
                                (b"content-length", str(len(body)).encode())]})
        await send({"type": "http.response.body", "body": body})

    def _with_cookie(self, send: Send) -> Send:
        async def wrapped(msg: MutableMapping[str, Any]) -> None:
            if msg["type"] == "http.response.start":
                cookie = f"{TOKEN_COOKIE}={self.token}; Path=/; HttpOnly; SameSite=Strict"
                msg["headers"] = list(msg.get("headers", [])) + [(b"set-cookie", cookie.encode())]
            await send(msg)
        return wrapped


#: the name earlier versions had (the token check only)
TokenGate = Gate
