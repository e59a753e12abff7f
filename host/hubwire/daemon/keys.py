"""A board's key (docs/SERVICE.md "Board identity and keys"): made of its name and board id, each
as a *level* that is safe as one MQTT topic level and a Home Assistant id, so the service, the MQTT
bridge and the dashboard name a board the same way."""
from __future__ import annotations

import hashlib
import re
from typing import Optional

__all__ = ["MAX_PLAIN", "board_key", "level", "safe_id"]

_UNSAFE = re.compile(r"[^A-Za-z0-9_-]")
#: a level kept as it is: safe characters, no "--", no "-" at either end, not shaped like a derived one
_PLAIN = re.compile(r"[A-Za-z0-9_]+(?:-[A-Za-z0-9_]+)*\Z")
_DERIVED = re.compile(r"-x[0-9a-f]{8}\Z")
#: longest level kept as it is; a longer one is cut and gets the hash
MAX_PLAIN = 32


def safe_id(text: str) -> str:
    """``text`` reduced to ``[A-Za-z0-9_-]`` (what Home Assistant allows in discovery topic ids).
    Many texts reduce alike: use :func:`level` for ids that must stay distinct."""
    return _UNSAFE.sub("_", text) or "_"


def level(text: str) -> str:
    """``text`` (a device name, a board id, a channel name) as one topic level and Home Assistant id.

    A plain text (``[A-Za-z0-9_]`` words joined by single ``-``, at most 32 characters) stays as it
    is; any other becomes its slug plus ``-x`` and 8 hex digits of its SHA-256 (``a/b`` ->
    ``a_b-xc14cddc0``). Plain texts never end like that, so a level never stands for two texts
    (short of a hash collision between two non-plain ones). The result never contains ``--``, never
    starts or ends with ``-``, and has no MQTT syntax (``+ # / $`` or NUL).
    """
    if len(text) <= MAX_PLAIN and _PLAIN.match(text) and not _DERIVED.search(text):
        return text
    slug = re.sub(r"-{2,}", "-", _UNSAFE.sub("_", text))[:24].strip("-") or "_"
    digest = hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:8]
    return f"{slug}-x{digest}"


def board_key(name: str, board_id: Optional[str], n: int = 1) -> str:
    """The key of the board ``name`` with ``board_id``: ``level(name)``, then ``--level(board_id)``
    when it has an id, then ``---n`` for the n-th board claiming the same name and id (n > 1).

    A function of the board's identity only, so a restart or replug never moves a key, and unique by
    construction: levels contain no ``--`` and neither start nor end with ``-``, so the first ``--``
    always ends the name's level.
    """
    key = level(name)
    if board_id is not None:
        key += "--" + level(board_id)
    if n > 1:
        key += f"---{n}"
    return key
