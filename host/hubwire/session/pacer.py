"""Writes to the device, with room between the fragments of a large message on a fast line
(PROTOCOL.md 12.3).

At 1,000,000 baud a byte reaches an Uno every 160 CPU cycles, fewer than its receive path needs
(about 130 for the frame, plus the Arduino core's receive interrupt): one frame fits its 64-byte
receive ring, but a burst of fragments overruns it, and every retry of the message meets the same
burst. So above :data:`PACE_ABOVE_BAUD` the hub sends the fragments of a message one at a time and
leaves the line idle for as long as the previous fragment took on it: half the line's rate while a
large message goes out, the full rate for everything else. Whatever the hub sends meanwhile waits
until the last fragment is out, so the fragments of a message stay together (a heartbeat may wait
a few milliseconds). Slower lines, and transports whose rate is unknown (0), are not paced.
"""
from __future__ import annotations

import asyncio
import threading
from typing import Any, List, Optional

__all__ = ["Pacer", "PACE_ABOVE_BAUD", "split_frames"]

#: lines faster than this are paced while a large message goes out (an 8-bit AVR at 16 MHz takes a
#: continuous stream up to about 600 kbaud; this leaves it room)
PACE_ABOVE_BAUD = 250_000


def split_frames(data: bytes) -> List[bytes]:
    """Wire bytes of several frames, one item per frame with its delimiter."""
    parts = data.split(b"\x00")
    return [p + b"\x00" for p in parts[:-1]] + ([parts[-1]] if parts[-1] else [])


class Pacer:
    """Writes through ``transport``; a write of several frames on a fast line goes out paced."""

    def __init__(self, transport: Any, loop: asyncio.AbstractEventLoop) -> None:
        self.transport = transport
        self.loop = loop
        self._lock = threading.Lock()
        self._queue: List[bytes] = []  # frames still to go out, one item each, in order
        self._busy = False  # a paced burst is going out: writes queue behind it
        self._timer: Optional[asyncio.TimerHandle] = None
        #: large messages sent paced (for tests and diagnostics)
        self.paced = 0

    @property
    def baud(self) -> int:
        return int(getattr(self.transport, "baudrate", 0) or 0)

    def pacing(self, data: bytes) -> bool:
        return self.baud > PACE_ABOVE_BAUD and data.count(0) > 1

    def burst_time(self, data: bytes) -> float:
        """Seconds until the last byte of ``data`` is on the line (twice the line time when paced)."""
        baud = self.baud
        if not baud:
            return 0.0
        return len(data) * 10.0 / baud * (2 if self.pacing(data) else 1)

    def write(self, data: bytes) -> None:
        """Send ``data`` (any thread): now, or after the paced burst in progress."""
        with self._lock:
            if self._busy:
                self._queue.extend(split_frames(data))
                return
            if not self.pacing(data):
                self.transport.write(data)
                return
            self._busy = True
            self.paced += 1
            self._queue = split_frames(data) + self._queue
        try:
            self.loop.call_soon_threadsafe(self._next)
        except RuntimeError:  # the loop is closed: the session is going away
            self.close()

    def _next(self) -> None:
        """On the loop: the next queued frame, then a pause as long as it takes on the line."""
        with self._lock:
            self._timer = None
            if not self._queue:
                self._busy = False
                return
            frame = self._queue.pop(0)
            self.transport.write(frame)
            self._timer = self.loop.call_later(len(frame) * 10.0 / self.baud, self._next)

    def close(self) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
            self._timer = None
            self._queue.clear()
            self._busy = False
