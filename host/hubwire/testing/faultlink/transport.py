"""faultlink as a transport: the faults of :class:`Faults` applied inside the hub process, between
the session and the real transport, driven by the session's event loop (no thread, no extra pty).

    fl = FaultyTransport(SerialTransport("/tmp/rover"), seed=1, both=Faults(ber=1e-4, drop=0.01))
    with hubwire.connect(transport=fl) as dev:
        fl.stall(2500)            # hold both directions for 2.5 s
        print(fl.stats())
"""
from __future__ import annotations

import asyncio
import math
import threading
import time
from dataclasses import replace
from typing import Any, Dict, Optional

from ...transport import DataCallback, LostCallback, Transport
from ..transports import WrappingTransport
from .faults import Faults, directions, link_stats, select_directions

__all__ = ["FaultyTransport"]


class FaultyTransport(WrappingTransport):
    """Wraps ``inner``; ``both`` sets the faults of both directions, ``hub_to_device`` /
    ``device_to_hub`` override it per direction. Counters as :meth:`FaultLink.stats`."""

    def __init__(self, inner: Transport, *, seed: int = 0, both: Optional[Faults] = None,
                 hub_to_device: Optional[Faults] = None, device_to_hub: Optional[Faults] = None) -> None:
        super().__init__(inner)
        self.seed = seed
        self._dirs = directions(seed, both, hub_to_device, device_to_hub)
        self._loop: Optional[asyncio.AbstractEventLoop] = None
        self._on_data: Optional[DataCallback] = None
        self._timer: Optional[asyncio.TimerHandle] = None
        self._loop_thread = 0
        self.opens = 0

    def open(self, loop: asyncio.AbstractEventLoop, on_data: DataCallback, on_lost: LostCallback) -> None:
        self.inner.open(loop, self._from_device, on_lost)
        self.opens += 1
        self._loop, self._on_data = loop, on_data
        self._loop_thread = threading.get_ident()
        now = time.monotonic()
        for d in self._dirs.values():
            d.discard()
            d.configure(d.faults, now)
        self._pump()

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self._on_data = None
        self.inner.close()

    def write(self, data: bytes) -> None:
        if self._loop is not None and threading.get_ident() != self._loop_thread:
            self._loop.call_soon_threadsafe(self.write, data)  # the fault engine lives on the loop
            return
        self._dirs["h2d"].ingest(data, time.monotonic())
        self._pump()

    def _from_device(self, data: bytes) -> None:
        self._dirs["d2h"].ingest(data, time.monotonic())
        self._pump()

    def _pump(self) -> None:
        """Release what is due both ways, then sleep until the next thing is due."""
        if self._on_data is None or self._loop is None:
            return
        now = time.monotonic()
        h2d, d2h = self._dirs["h2d"], self._dirs["d2h"]
        h2d.tick(now)
        d2h.tick(now)
        out = h2d.take_due(now)
        if out:
            self.inner.write(out)
        back = d2h.take_due(now)
        if back and self._on_data is not None:
            self._on_data(back)
        due = min(h2d.next_deadline(now), d2h.next_deadline(now))
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if due < math.inf and self._on_data is not None:
            self._timer = self._loop.call_at(self._loop.time() + max(0.0, due - now), self._pump)

    def _in_loop(self, fn: Any, *args: Any) -> None:
        if self._loop is None:
            fn(*args)
        else:
            self._loop.call_soon_threadsafe(fn, *args)

    def stall(self, ms: float, direction: str = "both") -> None:
        """Stop forwarding for ``ms`` milliseconds (bytes are held and delivered afterwards)."""
        def do() -> None:
            now = time.monotonic()
            for d in select_directions(self._dirs, direction):
                d.stall(ms, now)
            self._pump()
        self._in_loop(do)

    def set_faults(self, direction: str = "both", **changes: Any) -> None:
        """Change faults while running, e.g. ``set_faults("h2d", drop=0.5)`` or ``set_faults(ber=0)``."""
        def do() -> None:
            now = time.monotonic()
            for d in select_directions(self._dirs, direction):
                d.configure(replace(d.faults, **changes), now)
            self._pump()
        self._in_loop(do)

    def faults(self, direction: str) -> Faults:
        return replace(self._dirs[direction].faults)

    def stats(self) -> Dict[str, Any]:
        """Counters: per direction (``h2d``, ``d2h``) and totals (``frames``, ``faults``)."""
        out = link_stats(self._dirs)
        out["opens"] = self.opens
        return out
