"""faultlink: a fault-injecting serial link between a Hubwire hub and a device on a pty.

    hub  <->  pty created here (``link``)  <->  faultlink  <->  the device's pty (``device``)

The proxy creates its own pty and links it at ``link`` (what the hub opens), opens the device's
pty at ``device`` (e.g. the emulator's ``--link`` path) and forwards bytes both ways, injecting
faults independently per direction (:class:`Faults`):

- ``ber``: bit-error rate, each bit flipped with this probability;
- ``drop``: probability that a byte is lost;
- ``dup``: probability that a whole frame (bytes up to and including a ``0x00``) is sent twice;
- ``truncate``: probability that a frame loses a random tail (its delimiter is kept);
- ``garbage_every`` / ``garbage_len``: a burst of random bytes (``garbage_len = (lo, hi)``) between
  frames every ``garbage_every`` seconds;
- ``delay``: seconds added to every byte's trip (order is kept);
- ``stall_every`` / ``stall_ms``: stop forwarding for ``stall_ms`` every ``stall_every`` seconds
  (bytes are held, not lost; :meth:`FaultLink.stall` does it on demand).

Faults come from a seeded RNG per direction, so a run is reproducible for a given byte stream.
Every injected fault is counted (:meth:`FaultLink.stats`). If the device's pty disappears (the
device process died) the proxy keeps the hub side open and re-opens the device path when it
comes back.

Use it from Python::

    with FaultLink(device="/tmp/rover", link="/tmp/rover-faulty", seed=1,
                   both=Faults(ber=1e-4, drop=0.01, dup=0.005)) as fl:
        dev = hubwire.connect(fl.link)
        ...
        print(fl.stats())

or as a command (``python -m hubwire.testing.faultlink --help``).
"""
from __future__ import annotations

import errno
import os
import select
import subprocess
import threading
import time
import tty
from dataclasses import asdict, replace
from typing import Any, Dict, List, Optional

from .faults import Direction, Faults, directions, link_stats, select_directions

__all__ = ["FaultLink", "stop_process"]


def _open_device(path: str) -> int:
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    try:
        if os.isatty(fd):
            tty.setraw(fd)
    except Exception:
        os.close(fd)
        raise
    return fd


class FaultLink:
    """The proxy (see the module docstring). ``both`` sets the faults of both directions;
    ``hub_to_device`` / ``device_to_hub`` override it per direction."""

    def __init__(self, device: str, link: str, *, seed: int = 0, both: Optional[Faults] = None,
                 hub_to_device: Optional[Faults] = None, device_to_hub: Optional[Faults] = None,
                 reopen_interval: float = 0.05) -> None:
        self.device = device
        self.link = link
        self.seed = seed
        self._dirs = directions(seed, both, hub_to_device, device_to_hub)
        self.reopen_interval = reopen_interval
        self.device_opens = 0
        self.device_losses = 0
        self._master = self._slave = -1
        self._dev: Optional[int] = None
        self._dev_retry_at = 0.0
        self._thread: Optional[threading.Thread] = None
        self._stop = threading.Event()
        self._wake_r, self._wake_w = -1, -1
        self._lock = threading.Lock()
        self.started_at = 0.0

    # lifecycle ----------------------------------------------------------------------------

    def start(self, device_timeout: float = 5.0) -> "FaultLink":
        """Create the hub-side pty at ``link``, open the device (waiting up to device_timeout s
        for its path to appear) and start forwarding."""
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # the hub sets its own modes; raw until then
        os.set_blocking(self._master, False)
        slave_name = os.ttyname(self._slave)
        try:
            os.unlink(self.link)
        except FileNotFoundError:
            pass
        os.symlink(slave_name, self.link)
        deadline = time.monotonic() + device_timeout
        while True:
            try:
                self._dev = _open_device(self.device)
                self.device_opens += 1
                break
            except OSError:
                if time.monotonic() > deadline:
                    self._close_fds()
                    raise
                time.sleep(0.02)
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        self.started_at = time.monotonic()
        now = self.started_at
        for d in self._dirs.values():
            d.configure(d.faults, now)
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name=f"faultlink {self.link}", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop forwarding, remove ``link`` and close everything (the hub sees its port vanish)."""
        self._stop.set()
        if self._wake_w >= 0:
            try:
                os.write(self._wake_w, b"x")
            except OSError:
                pass
        if self._thread is not None:
            self._thread.join(5)
            self._thread = None
        try:
            if os.path.islink(self.link):
                os.unlink(self.link)
        except OSError:
            pass
        self._close_fds()

    def _close_fds(self) -> None:
        for name in ("_master", "_slave", "_wake_r", "_wake_w"):
            fd = getattr(self, name)
            if fd >= 0:
                try:
                    os.close(fd)
                except OSError:
                    pass
                setattr(self, name, -1)
        self._close_device()

    def _close_device(self) -> bool:
        """Close the emulator side of the proxy; True if it was open."""
        if self._dev is None:
            return False
        try:
            os.close(self._dev)
        except OSError:
            pass
        self._dev = None
        return True

    def __enter__(self) -> "FaultLink":
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    # control ------------------------------------------------------------------------------

    def set_faults(self, direction: str = "both", **changes: Any) -> None:
        """Change faults while running, e.g. ``set_faults("h2d", drop=0.5)`` or ``set_faults(ber=0)``."""
        now = time.monotonic()
        with self._lock:
            for d in self._select(direction):
                d.configure(replace(d.faults, **changes), now)
        self._wake()

    def faults(self, direction: str) -> Faults:
        return replace(self._dirs[direction].faults)

    def stall(self, ms: float, direction: str = "both") -> None:
        """Stop forwarding for ms milliseconds (bytes are held and delivered afterwards)."""
        now = time.monotonic()
        with self._lock:
            for d in self._select(direction):
                d.stall(ms, now)
        self._wake()

    def _select(self, direction: str) -> List[Direction]:
        return select_directions(self._dirs, direction)

    def stats(self) -> Dict[str, Any]:
        """Counters: per direction (``h2d``, ``d2h``) and totals (``frames``, ``faults``)."""
        with self._lock:
            out = link_stats(self._dirs)
        out["device_opens"] = self.device_opens
        out["device_losses"] = self.device_losses
        out["seconds"] = round(time.monotonic() - self.started_at, 3) if self.started_at else 0.0
        return out

    def config(self) -> Dict[str, Any]:
        return {"seed": self.seed, "h2d": asdict(self._dirs["h2d"].faults), "d2h": asdict(self._dirs["d2h"].faults)}

    def _wake(self) -> None:
        if self._wake_w >= 0:
            try:
                os.write(self._wake_w, b"x")
            except OSError:
                pass

    # the forwarding loop ------------------------------------------------------------------

    def _device_lost(self, now: float) -> None:
        if self._close_device():
            self.device_losses += 1
        self._dirs["h2d"].discard()
        self._dev_retry_at = now + self.reopen_interval

    def _read_ready(self, r: List[int], now: float) -> None:
        """Feed what the hub and the device sent (the fds select() found readable) to the faults."""
        if self._master in r:
            try:
                data = os.read(self._master, 4096)
            except OSError:  # BlockingIOError; EIO cannot happen while we hold the slave open
                data = b""
            if data:
                self._dirs["h2d"].ingest(data, now)
        if self._dev is not None and self._dev in r:
            try:
                data = os.read(self._dev, 4096)
                if not data:
                    raise OSError(errno.EIO, "device closed")
            except (BlockingIOError, InterruptedError):
                data = b""
            except OSError:
                self._device_lost(now)
                data = b""
            if data:
                self._dirs["d2h"].ingest(data, now)

    def _run(self) -> None:
        h2d, d2h = self._dirs["h2d"], self._dirs["d2h"]
        while not self._stop.is_set():
            now = time.monotonic()
            with self._lock:
                deadline = min(h2d.next_deadline(now), d2h.next_deadline(now))
            if self._dev is None:
                deadline = min(deadline, self._dev_retry_at)
            timeout = min(max(deadline - now, 0.0), 0.05)
            rfds = [self._master, self._wake_r]
            wfds = []
            if self._dev is not None:
                rfds.append(self._dev)
                if h2d.releasable(now):
                    wfds.append(self._dev)
            if d2h.releasable(now):
                wfds.append(self._master)
            try:
                r, w, _ = select.select(rfds, wfds, [], timeout)
            except (OSError, ValueError):
                if self._stop.is_set():
                    return
                raise
            now = time.monotonic()
            if self._wake_r in r:
                try:
                    os.read(self._wake_r, 64)
                except OSError:
                    pass
            with self._lock:
                self._read_ready(r, now)
                h2d.tick(now)
                d2h.tick(now)
                if self._dev is not None and not h2d.write_to(self._dev, now):
                    self._device_lost(now)
                if self._dev is None:
                    h2d.discard()
                    if now >= self._dev_retry_at:
                        try:
                            self._dev = _open_device(self.device)
                            self.device_opens += 1
                        except OSError:
                            self._dev_retry_at = now + self.reopen_interval
                d2h.write_to(self._master, now)


def stop_process(p: "subprocess.Popen[Any]", timeout: float = 5.0) -> None:
    """SIGTERM a child (emulator, simulator) and reap it; SIGKILL if it does not end in time."""
    if p.poll() is not None:
        return
    p.terminate()
    try:
        p.wait(timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait(timeout)
