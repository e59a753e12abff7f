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

or as a command (``PYTHONPATH=tools python -m faultlink --help``).
"""
from __future__ import annotations

import errno
import subprocess
import math
import os
import random
import select
import threading
import time
import tty
from collections import deque
from dataclasses import asdict, dataclass, field, replace
from typing import Any, Deque, Dict, List, Optional, Tuple

__all__ = ["Faults", "FaultLink", "DirectionStats"]

#: bytes held per direction before new ones are dropped (a reader that stopped reading)
MAX_QUEUED = 64 * 1024
#: a partial frame (no 0x00 yet) is forwarded after this long without frame-level faults
PARTIAL_FLUSH = 0.02


@dataclass
class Faults:
    """Faults injected in one direction (all off by default)."""

    ber: float = 0.0
    drop: float = 0.0
    dup: float = 0.0
    truncate: float = 0.0
    garbage_every: float = 0.0
    garbage_len: Tuple[int, int] = (8, 64)
    delay: float = 0.0
    stall_every: float = 0.0
    stall_ms: float = 0.0

    def validate(self) -> "Faults":
        for name in ("ber", "drop", "dup", "truncate"):
            v = getattr(self, name)
            if not 0.0 <= v < 1.0:
                raise ValueError(f"{name} must be a probability in [0, 1), got {v}")
        lo, hi = self.garbage_len
        if not 1 <= lo <= hi:
            raise ValueError(f"garbage_len must be (lo, hi) with 1 <= lo <= hi, got {self.garbage_len}")
        for name in ("garbage_every", "delay", "stall_every", "stall_ms"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0")
        return self


@dataclass
class DirectionStats:
    """What went through one direction and what was done to it."""

    bytes_in: int = 0
    bytes_out: int = 0
    frames: int = 0              # delimiters (0x00) received from the sender
    bits_flipped: int = 0
    bytes_dropped: int = 0
    frames_duplicated: int = 0
    frames_truncated: int = 0
    bytes_truncated: int = 0
    garbage_bursts: int = 0
    garbage_bytes: int = 0
    stalls: int = 0
    overflow_dropped: int = 0    # bytes discarded because the receiver did not read (not a fault)

    @property
    def faults(self) -> int:
        """Injected faults: flipped bits, dropped bytes, duplicated/truncated frames, garbage bursts, stalls."""
        return (self.bits_flipped + self.bytes_dropped + self.frames_duplicated + self.frames_truncated
                + self.garbage_bursts + self.stalls)


class _Geometric:
    """Positions of independent events of probability p in a stream, by skipping (fast for small p)."""

    def __init__(self, rng: random.Random, p: float) -> None:
        self.rng = rng
        self.set(p)

    def set(self, p: float) -> None:
        self.p = p
        self._log = math.log1p(-p) if p > 0 else 0.0
        self.left = self._draw()

    def _draw(self) -> int:
        if self.p <= 0:
            return 1 << 62
        return int(math.log(1.0 - self.rng.random()) / self._log)

    def hits(self, n: int) -> List[int]:
        """Indexes in the next n positions where an event happens."""
        out = []
        pos = self.left
        while pos < n:
            out.append(pos)
            pos += 1 + self._draw()
        self.left = pos - n
        return out


class _Direction:
    def __init__(self, name: str, faults: Faults, rng: random.Random) -> None:
        self.name = name
        self.rng = rng
        self.stats = DirectionStats()
        self.partial = bytearray()
        self.partial_at = 0.0
        self.out: Deque[List[Any]] = deque()  # [release_time, bytearray]
        self.queued = 0
        self.stall_until = 0.0
        self.lock = threading.Lock()
        self._bits = _Geometric(rng, 0.0)
        self._drops = _Geometric(rng, 0.0)
        self.configure(faults, time.monotonic())

    def configure(self, faults: Faults, now: float) -> None:
        self.faults = faults.validate()
        self._bits.set(faults.ber)
        self._drops.set(faults.drop)
        self.next_garbage = now + faults.garbage_every if faults.garbage_every > 0 else math.inf
        self.next_stall = now + faults.stall_every if faults.stall_every > 0 and faults.stall_ms > 0 else math.inf

    # bytes from the sender ----------------------------------------------------------------

    def ingest(self, data: bytes, now: float) -> None:
        self.stats.bytes_in += len(data)
        start = 0
        while True:
            i = data.find(b"\x00", start)
            if i < 0:
                break
            self.partial += data[start:i + 1]
            self.stats.frames += 1
            self._frame(bytes(self.partial), now)
            self.partial.clear()
            start = i + 1
        if start < len(data):
            if not self.partial:
                self.partial_at = now
            self.partial += data[start:]

    def _frame(self, frame: bytes, now: float) -> None:
        f = self.faults
        rng = self.rng
        if f.truncate > 0 and len(frame) > 2 and rng.random() < f.truncate:
            keep = rng.randrange(0, len(frame) - 1)  # body bytes kept; the delimiter stays
            self.stats.frames_truncated += 1
            self.stats.bytes_truncated += len(frame) - 1 - keep
            frame = frame[:keep] + b"\x00"
        copies = 1
        if f.dup > 0 and rng.random() < f.dup:
            copies = 2
            self.stats.frames_duplicated += 1
        for _ in range(copies):
            self._emit(self._corrupt(frame), now)

    def _corrupt(self, data: bytes) -> bytes:
        n = len(data)
        if n == 0:
            return data
        flips = self._bits.hits(n * 8)
        drops = self._drops.hits(n)
        if not flips and not drops:
            return data
        buf = bytearray(data)
        for bit in flips:
            buf[bit >> 3] ^= 1 << (bit & 7)
        self.stats.bits_flipped += len(flips)
        if drops:
            for i in reversed(drops):
                del buf[i]
            self.stats.bytes_dropped += len(drops)
        return bytes(buf)

    def _emit(self, data: bytes, now: float) -> None:
        if not data:
            return
        if self.queued + len(data) > MAX_QUEUED:
            self.stats.overflow_dropped += len(data)
            return
        release = now + self.faults.delay
        if self.out and self.out[-1][0] >= release - 0.0005:
            self.out[-1][1] += data  # coalesce (keeps order, fewer writes)
        else:
            self.out.append([release, bytearray(data)])
        self.queued += len(data)

    # timers -------------------------------------------------------------------------------

    def tick(self, now: float) -> None:
        f = self.faults
        if self.partial and now - self.partial_at >= PARTIAL_FLUSH:
            data = bytes(self.partial)
            self.partial.clear()
            self._emit(self._corrupt(data), now)
        if now >= self.next_garbage:
            lo, hi = f.garbage_len
            n = self.rng.randint(lo, hi)
            self._emit(bytes(self.rng.getrandbits(8) for _ in range(n)), now)
            self.stats.garbage_bursts += 1
            self.stats.garbage_bytes += n
            self.next_garbage = now + f.garbage_every
        if now >= self.next_stall:
            self.stall(f.stall_ms, now)
            self.next_stall = now + f.stall_every

    def stall(self, ms: float, now: float) -> None:
        self.stall_until = max(self.stall_until, now + ms / 1000.0)
        self.stats.stalls += 1

    def next_deadline(self, now: float) -> float:
        t = min(self.next_garbage, self.next_stall)
        if self.partial:
            t = min(t, self.partial_at + PARTIAL_FLUSH)
        if self.out:
            t = min(t, max(self.out[0][0], self.stall_until))
        return t

    def releasable(self, now: float) -> bool:
        return bool(self.out) and now >= self.stall_until and self.out[0][0] <= now

    def write_to(self, fd: int, now: float) -> bool:
        """Write what is due to fd; False when the fd is gone (EIO)."""
        while self.releasable(now):
            chunk = self.out[0][1]
            try:
                n = os.write(fd, chunk)
            except BlockingIOError:
                return True
            except OSError as e:
                if e.errno in (errno.EIO, errno.EBADF, errno.ENXIO):
                    return False
                raise
            self.stats.bytes_out += n
            self.queued -= n
            if n == len(chunk):
                self.out.popleft()
            else:
                del chunk[:n]
                return True
        return True

    def discard(self) -> None:
        self.out.clear()
        self.queued = 0
        self.partial.clear()


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
        base = both or Faults()
        self._dirs = {
            "h2d": _Direction("h2d", replace(hub_to_device or base), random.Random(seed * 2 + 1)),
            "d2h": _Direction("d2h", replace(device_to_hub or base), random.Random(seed * 2 + 2)),
        }
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

    def _select(self, direction: str) -> List[_Direction]:
        if direction == "both":
            return list(self._dirs.values())
        if direction not in self._dirs:
            raise ValueError("direction must be 'h2d', 'd2h' or 'both'")
        return [self._dirs[direction]]

    def stats(self) -> Dict[str, Any]:
        """Counters: per direction (``h2d``, ``d2h``) and totals (``frames``, ``faults``)."""
        with self._lock:
            out: Dict[str, Any] = {}
            for name, d in self._dirs.items():
                s = asdict(d.stats)
                s["faults"] = d.stats.faults
                out[name] = s
        out["frames"] = out["h2d"]["frames"] + out["d2h"]["frames"]
        out["faults"] = out["h2d"]["faults"] + out["d2h"]["faults"]
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
                if self._master in r:
                    try:
                        data = os.read(self._master, 4096)
                    except (BlockingIOError, InterruptedError):
                        data = b""
                    except OSError:
                        data = b""  # cannot happen while we hold the slave open
                    if data:
                        h2d.ingest(data, now)
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
                        d2h.ingest(data, now)
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
