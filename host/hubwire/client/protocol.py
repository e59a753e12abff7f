"""The local client protocol of ``hubwire serve`` (docs/SERVICE.md): JSON lines on a Unix socket.

Shared by the server and the client: where the socket is, how a board and an error look on the wire.
"""
from __future__ import annotations

import json
import math
import os
from typing import Any, Dict, Optional

from .. import errors
from ..errors import HubwireError, ServiceError, ServiceNotRunning
from .sockdir import log, untrusted

__all__ = ["PROTOCOL", "jsonable", "socket_path", "default_serve_socket", "board_json", "error_json", "raise_error",
           "ServiceNotRunning", "ServiceError", "encode", "SYSTEM_SOCKET", "Usage", "Busy"]

#: version of this protocol; a client refuses a service that speaks another
PROTOCOL = 1
#: where the system service (systemd, RuntimeDirectory=hubwire) listens
SYSTEM_SOCKET = "/run/hubwire/hubwire.sock"
#: where a user's service listens without $XDG_RUNTIME_DIR: TMP/hubwire-UID (made 0700 by the service)
TMP = "/tmp"
#: the longest line either side accepts
MAX_LINE = 1 << 20


class Usage(HubwireError):
    """A request the protocol does not allow (a field of the wrong type, a ``sub`` id in use)."""

    kind = "Usage"


class Busy(HubwireError):
    """A per-client limit of the service was reached (docs/SERVICE.md "Limits")."""

    kind = "Busy"


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


def jsonable(v: Any) -> Any:
    """A value as JSON on the socket (and in the command line's ``--json``): structs as objects, arrays
    as lists, NaN and the infinities as text."""
    if isinstance(v, tuple) and hasattr(v, "_asdict"):
        return {k: jsonable(x) for k, x in v._asdict().items()}
    if isinstance(v, (tuple, list)):
        return [jsonable(x) for x in v]
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    return v


def board_json(b: Any) -> Dict[str, Any]:
    return {"key": b.key, "name": b.name, "board_id": b.board_id, "port": b.port, "state": b.state,
            "attached": b.attached, "sessions": b.sessions}


def error_json(exc: BaseException) -> Dict[str, Any]:
    return {"ok": False, **errors.error_json(exc)}


def raise_error(msg: Dict[str, Any]) -> None:
    """Raise the exception an error reply stands for (the same class a direct connection raises)."""
    raise errors.error_from(msg)
