"""Bounding device-supplied text before it reaches an exception or a log line: a hostile or broken
device may name itself or a channel with 10,000 characters, or with control characters."""
from __future__ import annotations

import json
from typing import Any, Iterable, List

__all__ = ["clip", "show", "clip_json", "clip_list", "CLIP_LIMIT"]

#: characters of a device-supplied string kept in messages
CLIP_LIMIT = 80


def _cut(text: str, limit: int, close: str = "") -> str:
    if len(text) <= limit:
        return text
    return f"{text[:limit]}…{close} (+{len(text) - limit} chars)"


def clip(text: Any, limit: int = CLIP_LIMIT) -> str:
    """``repr(text)`` (quoted, control characters escaped) cut to ``limit`` characters, saying how
    much was cut: ``'aaaa…' (+9920 chars)``."""
    r = repr(text if isinstance(text, str) else str(text))
    return _cut(r, limit, r[0])


def show(text: Any, limit: int = CLIP_LIMIT) -> str:
    """``text`` as it is when it is short and printable, else :func:`clip` (quoted, escaped, cut)."""
    s = text if isinstance(text, str) else str(text)
    return s if len(s) <= limit and s.isprintable() else clip(s, limit)


def clip_json(value: Any, limit: int = CLIP_LIMIT) -> str:
    """A JSON value as JSON text (control characters escaped), cut to ``limit`` characters."""
    return _cut(json.dumps(value), limit)


def clip_list(items: Iterable[Any], limit: int = 4 * CLIP_LIMIT) -> str:
    """``a, b, c``: the items (each already bounded by the caller) joined, cut after about ``limit``
    characters with how many were left out."""
    all_ = [str(x) for x in items]
    out: List[str] = []
    used = 0
    for i, s in enumerate(all_):
        if used + len(s) > limit and out:
            out.append(f"… (+{len(all_) - i} more)")
            break
        out.append(s)
        used += len(s) + 2
    return ", ".join(out)
