"""Bounding device-supplied text before it reaches an exception or a log line: a hostile or broken
device may name itself or a channel with 10,000 characters, or with control characters."""
from __future__ import annotations

__all__ = ["clip", "CLIP_LIMIT"]

#: characters of a device-supplied string kept in messages
CLIP_LIMIT = 80


def clip(text: object, limit: int = CLIP_LIMIT) -> str:
    """``repr(text)`` (quotes, control characters escaped) cut to about ``limit`` characters,
    saying how much was cut: ``'aaaa…' (+9920 chars)``."""
    r = repr(text if isinstance(text, str) else str(text))
    if len(r) <= limit:
        return r
    return f"{r[:limit]}…{r[0]} (+{len(r) - limit} chars)"
