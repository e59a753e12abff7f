"""The local client protocol of ``hubwire serve`` (docs/SERVICE.md): JSON lines on a Unix socket.

Shared by the server and the client: where the socket is, how a board and an error look on the wire.
"""
from __future__ import annotations

import json
import os
from typing import Any, Dict, Optional

from ..errors import HubwireError, InvalidValue, LinkLost, NakError, Timeout

__all__ = ["PROTOCOL", "socket_path", "default_serve_socket", "board_json", "error_json", "raise_error",
           "ServiceNotRunning", "ServiceError", "encode", "SYSTEM_SOCKET", "Usage", "Busy"]

#: version of this protocol; a client refuses a service that speaks another
PROTOCOL = 1
#: where the system service (systemd, RuntimeDirectory=hubwire) listens
SYSTEM_SOCKET = "/run/hubwire/hubwire.sock"
#: where a user's service listens without $XDG_RUNTIME_DIR: TMP/hubwire-UID (made 0700 by the service)
TMP = "/tmp"
#: the longest line either side accepts
MAX_LINE = 1 << 20


class ServiceNotRunning(HubwireError):
    """No ``hubwire serve`` answers on the socket."""

    kind = "ServiceNotRunning"


class Usage(HubwireError):
    """A request the protocol does not allow (a field of the wrong type, a ``sub`` id in use)."""

    kind = "Usage"


class Busy(HubwireError):
    """A per-client limit of the service was reached (docs/SERVICE.md "Limits")."""

    kind = "Busy"


class ServiceError(HubwireError):
    """An error the service reported that has no class of its own here (``kind`` is its type)."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


def _user_socket() -> Optional[str]:
    run = os.environ.get("XDG_RUNTIME_DIR")
    return os.path.join(run, "hubwire", "hubwire.sock") if run else None


def _tmp_socket() -> str:
    return os.path.join(TMP, f"hubwire-{os.getuid()}", "hubwire.sock")


def socket_path() -> Optional[str]:
    """The socket a client tries: $HUBWIRE_SOCKET, else the user's service ($XDG_RUNTIME_DIR/hubwire,
    then /tmp/hubwire-UID), else the system one (the first that exists); None when there is none.
    A socket in a directory another user made, or others may write to, is skipped (with a warning):
    whoever made it could stand in for the service."""
    env = os.environ.get("HUBWIRE_SOCKET")
    if env:
        return env
    from .sockdir import log, untrusted

    for p in (_user_socket(), _tmp_socket(), SYSTEM_SOCKET):
        if p and os.path.exists(p):
            why = untrusted(os.path.dirname(p)) if p != SYSTEM_SOCKET else None
            if why is None:
                return p
            log.warning("hubwire: not using the service socket %s: %s", p, why)
    return None


def default_serve_socket() -> str:
    """Where ``hubwire serve`` listens by default: $HUBWIRE_SOCKET, /run/hubwire as root, else
    $XDG_RUNTIME_DIR/hubwire (or /tmp/hubwire-UID without one)."""
    env = os.environ.get("HUBWIRE_SOCKET")
    if env:
        return env
    if os.geteuid() == 0:
        return SYSTEM_SOCKET
    return _user_socket() or _tmp_socket()


def encode(obj: Dict[str, Any]) -> bytes:
    text = json.dumps(obj, ensure_ascii=False, separators=(",", ":")) + "\n"
    try:
        return text.encode("utf-8")
    except UnicodeEncodeError:  # a lone surrogate (a "\\udc80" escape in a request): escaped again
        return (json.dumps(obj, separators=(",", ":")) + "\n").encode("ascii")


def board_json(b: Any) -> Dict[str, Any]:
    return {"key": b.key, "name": b.name, "board_id": b.board_id, "port": b.port, "state": b.state,
            "attached": b.attached, "sessions": b.sessions}


def error_json(exc: BaseException) -> Dict[str, Any]:
    from ..diagnose import error_type

    kind = getattr(exc, "kind", None)
    if not isinstance(kind, str):
        kind = "UnknownChannel" if isinstance(exc, KeyError) else error_type(exc)
    text = str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)
    out: Dict[str, Any] = {"ok": False, "error": kind, "message": text}
    if isinstance(exc, NakError):
        out.update(nak=exc.error, code=exc.code, channel=exc.channel)
    elif isinstance(exc, InvalidValue):
        out.update(code=exc.code)
    return out


def raise_error(msg: Dict[str, Any]) -> None:
    """Raise the exception an error reply stands for (the same class a direct connection raises)."""
    kind, text = str(msg.get("error", "Error")), str(msg.get("message", ""))
    if kind == "Nak":
        e: HubwireError = NakError(int(msg.get("code", 0)), msg.get("channel"))
        e.args = (text,)
        raise e
    if kind == "InvalidValue":
        raise InvalidValue(text, int(msg.get("code", 0)))
    if kind == "Timeout":
        raise Timeout(text)
    if kind == "LinkLost":
        raise LinkLost(text)
    if kind == "UnknownBoard":
        from .fleet import UnknownBoard

        raise UnknownBoard(text)
    raise ServiceError(kind, text)
