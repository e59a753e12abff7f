"""Transport wrappers for tests and benchmarks: watch, filter, pause or count what crosses the seam.

    tap = TapTransport(SerialTransport(path))
    dev = hubwire.connect(transport=tap)
    tap.paused = True                       # the hub falls silent (nothing is written)
    tap.tx_filter = lambda wire: ...        # False: this write is not sent
    tap.rx_filter = lambda frame: ...       # False: this received frame never reaches the hub

``tx_filter`` runs on the thread that writes (the caller's, for the synchronous API's
transactions), ``rx_filter`` on the hub's event loop; they must not block.
"""
from __future__ import annotations

import asyncio
import time
from typing import Callable, List, Optional

from ..transport import DataCallback, LostCallback, Transport
from ..wire.frame import Frame, decode_frame

__all__ = ["TapTransport", "WrappingTransport"]


class WrappingTransport(Transport):
    """A transport passing everything to ``inner``; subclasses override what they change."""

    def __init__(self, inner: Transport) -> None:
        self.inner = inner
        self.url = inner.url

    def open(self, loop: asyncio.AbstractEventLoop, on_data: DataCallback, on_lost: LostCallback) -> None:
        self.inner.open(loop, on_data, on_lost)

    def write(self, data: bytes) -> None:
        self.inner.write(data)

    def close(self) -> None:
        self.inner.close()

    @property
    def is_open(self) -> bool:
        return self.inner.is_open

    @property
    def baudrate(self) -> int:
        """The inner transport's line rate (0: unknown), which the hub paces large messages by."""
        return int(getattr(self.inner, "baudrate", 0) or 0)


class TapTransport(WrappingTransport):
    """Pause or filter what the hub sends and receives, and record when the transport is opened.

    - ``paused``: nothing is written (a hub that fell silent);
    - ``tx_filter(wire_bytes) -> bool``: a write for which it returns False is not sent (the hub
      writes one frame per write; a hello is preceded by a lone ``00``);
    - ``rx_filter(frame) -> bool``: a received frame for which it returns False is not passed on
      (bytes are passed on frame by frame, exactly as received, once their ``00`` arrived);
    - ``opens``: ``time.monotonic()`` of every successful or failed open attempt.
    """

    def __init__(self, inner: Transport) -> None:
        super().__init__(inner)
        self.paused = False
        self.tx_filter: Optional[Callable[[bytes], bool]] = None
        self.rx_filter: Optional[Callable[[Frame], bool]] = None
        self.opens: List[float] = []
        self._pending = b""

    def open(self, loop: asyncio.AbstractEventLoop, on_data: DataCallback, on_lost: LostCallback) -> None:
        self.opens.append(time.monotonic())
        self._pending = b""
        self.inner.open(loop, lambda data: self._received(data, on_data), on_lost)

    def _received(self, data: bytes, on_data: DataCallback) -> None:
        flt = self.rx_filter
        if flt is None and not self._pending:
            on_data(data)
            return
        data = self._pending + data
        cut = data.rfind(b"\x00") + 1
        self._pending = data[cut:]
        out = []
        for part in data[:cut].split(b"\x00")[:-1]:
            f = decode_frame(part) if part and flt is not None else None
            if f is None or flt is None or flt(f):
                out.append(part + b"\x00")
        if out:
            on_data(b"".join(out))

    def write(self, data: bytes) -> None:
        if self.paused or (self.tx_filter is not None and not self.tx_filter(data)):
            return
        self.inner.write(data)
