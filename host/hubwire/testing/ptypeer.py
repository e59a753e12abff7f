"""A scripted peer on a pty: the base of test devices written in Python (the hub-channel soak's
device, the tests' scripted devices). A thread reads frames and hands each to ``handle``; once
``linked`` it sends a heartbeat every ``beat_ms`` (``since_ms`` 0 first, then ``beat_ms``)."""
from __future__ import annotations

import os
import select
import threading
import time
import tty
from typing import Any

from ..wire import messages as m
from ..wire.frame import Frame, FrameDecoder, encode_frame

__all__ = ["PtyPeer"]


class PtyPeer:
    """Subclasses implement :meth:`handle`; ``path`` is the pty a hub opens."""

    def __init__(self, max_payload: int = 32, beat_ms: int = 250) -> None:
        self.max_payload = max_payload
        self.beat_ms = beat_ms
        self.linked = False
        #: a cut line: nothing is sent, everything received is lost
        self.mute = False
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self.lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"pty peer {self.path}", daemon=True)

    def start(self) -> "PtyPeer":
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(2)
        os.close(self.master)
        os.close(self.slave)

    def __enter__(self) -> Any:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def send(self, t: int, seq: int, cid: int, payload: bytes = b"") -> None:
        if self.mute:
            return
        with self.lock:
            try:
                os.write(self.master, encode_frame(t, seq, cid, payload))
            except OSError:
                pass  # closed under us at the end of a run

    def handle(self, f: Frame) -> None:
        raise NotImplementedError

    def tick(self) -> None:
        """Called on the peer's thread every pass of its loop (about every 20 ms): retries, timers."""

    def _run(self) -> None:
        dec = FrameDecoder(self.max_payload)
        beat, n = 0.0, 0
        while not self._stop.is_set():
            r, _, _ = select.select([self.master], [], [], 0.02)
            if r:
                try:
                    data = os.read(self.master, 512)
                except OSError:
                    return
                for f in dec.feed(data) if not self.mute else ():
                    self.linked = self.linked or f.type == m.HELLO
                    self.handle(f)
            self.tick()
            if self.linked and time.monotonic() - beat >= self.beat_ms / 1000:
                n += 1
                self.send(m.HEARTBEAT, n & 0xFF, 0, m.Heartbeat(n, 0 if n == 1 else self.beat_ms, 0, 0, 0).pack())
                beat = time.monotonic()
