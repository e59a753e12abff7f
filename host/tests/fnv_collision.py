"""A second descriptor with the same length and FNV-1a hash as a given one (test helper).

FNV-1a is invertible byte by byte: ``h' = (h ^ b) * P`` gives ``h = (h' * P^-1) ^ b``. Six bytes of a
description are changed; the first three are tried forwards from the state before them, the last
three backwards from the state the rest of the text needs after them, and the two meet on 32 bits
(64^3 x 64^3 / 2^32 = 16 expected matches). Well under a second in Python.
"""
from __future__ import annotations

from typing import Dict, Iterator, Optional, Tuple

from hubwire.wire.messages import fnv1a32

OFFSET, PRIME = 0x811C9DC5, 0x01000193
PRIME_INV = pow(PRIME, -1, 1 << 32)
MASK = 0xFFFFFFFF
# 64 characters that need no escaping inside a JSON string
ALPHABET = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_"
assert len(ALPHABET) == 64


def _forward(h: int, data: bytes) -> int:
    for b in data:
        h = ((h ^ b) * PRIME) & MASK
    return h


def _backward(h: int, data: bytes) -> int:
    for b in reversed(data):
        h = ((h * PRIME_INV) & MASK) ^ b
    return h


def _triples() -> Iterator[bytes]:
    for a in ALPHABET:
        for b in ALPHABET:
            for c in ALPHABET:
                yield bytes((a, b, c))


def collide(data: bytes, at: int, target: Optional[int] = None) -> Optional[bytes]:
    """``data`` with bytes ``at .. at+6`` replaced so that its FNV-1a hash becomes ``target`` (by
    default its own) at the same length, or None when no replacement differs from the original."""
    want = fnv1a32(data) if target is None else target
    before = _forward(OFFSET, data[:at])
    after = _backward(want, data[at + 6:])  # the state needed once the six bytes are in
    middle: Dict[int, bytes] = {}
    for t in _triples():
        middle.setdefault(_forward(before, t), t)
    for t in _triples():
        head = middle.get(_backward(after, t))
        if head is not None and head + t != data[at:at + 6]:
            forged = data[:at] + head + t + data[at + 6:]
            assert len(forged) == len(data) and fnv1a32(forged) == want
            return forged
    return None


def collide_in_text(data: bytes, text: bytes, target: Optional[int] = None) -> Tuple[bytes, int]:
    """:func:`collide` inside the first occurrence of ``text`` (at least 6 bytes long)."""
    at = data.index(text)
    forged = collide(data, at, target)
    if forged is None:
        raise ValueError("no collision found at that place")
    return forged, at
