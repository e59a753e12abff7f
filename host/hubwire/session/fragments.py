"""Large values (PROTOCOL.md 12): a message whose payload does not fit one frame travels as
fragments ``F``, each carrying the message's type, the offset of its bytes and the total length,
under the message's own seq and id.

:func:`encode_message` gives the wire bytes of a message, one frame or all its fragments back to
back (so a retry, which re-sends those bytes, re-sends every fragment). :class:`Reassembler` puts
received fragments back together: one message at a time, offsets contiguous from 0, anything else
dropped and counted, so a lost, repeated or corrupt fragment loses the whole message and no torn
value is ever handed on. A reassembly is also abandoned when the transaction it answers is given up
or retried under a new seq (:meth:`Reassembler.abandon`), and when its next fragment is later than
:data:`FRAGMENT_GAP`: no fragment of a later message that happens to carry the same seq and id (the
seq wraps) ever completes it.
"""
from __future__ import annotations

import threading
import time
from typing import Any, List, Optional

from ..wire import messages as m
from ..wire.frame import PROTOCOL_MAX_PAYLOAD, Frame, encode_frame

__all__ = ["MAX_TOTAL", "MIN_ACCEPTED", "FRAGMENT_GAP", "accepted", "fragments", "encode_message", "Reassembler"]

#: the largest payload fragments can carry: their total is a u16
MAX_TOTAL = 0xFFFF
#: the smallest accepted payload a hello may announce (smaller is taken as this, PROTOCOL.md 3.1)
MIN_ACCEPTED = 16
#: seconds between two fragments of one message past which the reassembly is abandoned: a sender
#: sends them back to back (a 255-byte frame takes 0.27 s at 9600 baud), and it stays below the
#: 2.56 s in which a device's fastest stream (10 ms) could bring a sample's seq round again
FRAGMENT_GAP = 2.0


def accepted(announced: Optional[int]) -> int:
    """What a peer that announced ``announced`` accepts (None: not heard yet, the protocol maximum)."""
    if announced is None:
        return PROTOCOL_MAX_PAYLOAD
    return max(MIN_ACCEPTED, min(PROTOCOL_MAX_PAYLOAD, announced))


def fragments(type: int, payload: bytes, limit: int) -> List[bytes]:
    """The fragment payloads of a message whose payload is longer than ``limit`` (the receiver's
    accepted payload, no more than the sender's own), offset 0 first; ValueError past MAX_TOTAL."""
    total = len(payload)
    if total > MAX_TOTAL:
        raise ValueError(f"a message of {total} bytes exceeds the largest value, {MAX_TOTAL}")
    step = limit - m.Fragment.HEADER
    return [m.Fragment(type, off, total, payload[off:off + step]).pack() for off in range(0, total, step)]


def encode_message(type: int, seq: int, id: int, payload: bytes, limit: int) -> bytes:
    """Wire bytes of a message: one frame when the payload fits ``limit``, else all its fragments."""
    if len(payload) <= limit:
        return encode_frame(type, seq, id, payload)
    return b"".join(encode_frame(m.FRAGMENT, seq, id, p) for p in fragments(type, payload, limit))


class Reassembler:
    """The one reassembly a receiver keeps (PROTOCOL.md 12). ``counters`` is the object whose
    ``dropped`` counter a refused fragment adds to (the frame decoder, so heartbeats report it)."""

    def __init__(self, counters: Any) -> None:
        self.counters = counters
        self._lock = threading.Lock()  # fed on the loop, abandoned from a caller's thread too
        self.reset()
        #: whole messages put together, and fragments refused
        self.completed = 0
        self.refused = 0

    def reset(self) -> None:
        """Abandon the reassembly in progress (a new connection)."""
        self._key: Optional["tuple[int, int, int, int]"] = None
        self._buf = bytearray()
        self._last_at = 0.0

    def _refuse(self) -> None:
        self.counters.dropped += 1
        self.refused += 1
        self.reset()

    def feed(self, f: Frame) -> Optional[Frame]:
        """Take one ``F`` frame; the carried message once its last fragment is in, else None."""
        with self._lock:
            return self._feed(f, time.monotonic())

    def abandon(self, seq: int, id: int) -> None:
        """Nobody waits for the message with this seq and id any more: drop what came of it (not counted)."""
        with self._lock:
            k = self._key
            if k is not None and k[1] == seq and k[2] == id:
                self.reset()

    def _feed(self, f: Frame, now: float) -> Optional[Frame]:
        try:
            fr = m.Fragment.unpack(f.payload)
        except m.PayloadError:
            self._refuse()
            return None
        if fr.type == m.FRAGMENT or fr.total == 0 or fr.offset + len(fr.data) > fr.total:
            self._refuse()
            return None
        key = (fr.type, f.seq, f.id, fr.total)
        if fr.offset == 0:
            self._key, self._buf = key, bytearray()
        elif key != self._key or fr.offset != len(self._buf) or now - self._last_at > FRAGMENT_GAP:
            self._refuse()
            return None
        self._buf += fr.data
        self._last_at = now
        if len(self._buf) < fr.total:
            return None
        whole = Frame(fr.type, f.seq, f.id, bytes(self._buf))
        self.reset()
        self.completed += 1
        return whole

    def receiving(self, seq: int, id: int, since: float) -> bool:
        """True while a message with this seq and id is coming in and a fragment arrived after ``since``."""
        k = self._key
        return k is not None and k[1] == seq and k[2] == id and self._last_at > since

