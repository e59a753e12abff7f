"""The fault engine of faultlink: what is done to the bytes of one direction (see :class:`Faults`),
shared by the in-process :class:`~hubwire.testing.faultlink.FaultyTransport` and the pty proxy
:class:`~hubwire.testing.faultlink.FaultLink`.

Faults come from a seeded RNG per direction, so a run is reproducible for a given byte stream, and
every injected fault is counted (:class:`DirectionStats`).
"""
from __future__ import annotations

import errno
import math
import os
import random
import time
from collections import deque
from dataclasses import asdict, dataclass, replace
from typing import Any, Deque, Dict, List, Optional, Tuple

__all__ = ["Faults", "SOAK_FAULTS", "DirectionStats", "Direction", "directions", "select_directions", "link_stats",
           "MAX_QUEUED", "PARTIAL_FLUSH"]

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
    cut: bool = False  # a dead wire: every byte (garbage too) is discarded and counted

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


#: the soak's link (soak.py, soak_hub.py): BER 1e-4, 1% byte drops, 0.5% duplicated frames, a garbage
#: burst (8..64 random bytes) every 1 s
SOAK_FAULTS = Faults(ber=1e-4, drop=0.01, dup=0.005, garbage_every=1.0, garbage_len=(8, 64))


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
    bytes_cut: int = 0           # bytes discarded while the wire was cut

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


class Direction:
    """The faults of one direction applied to the bytes of its sender, with their release times."""

    def __init__(self, name: str, faults: Faults, rng: random.Random) -> None:
        self.name = name
        self.rng = rng
        self.stats = DirectionStats()
        self.partial = bytearray()
        self.partial_at = 0.0
        self.out: Deque[List[Any]] = deque()  # [release_time, bytearray]
        self.queued = 0
        self.stall_until = 0.0
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
        if self.faults.cut:
            self.stats.bytes_cut += len(data)
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

    def take_due(self, now: float) -> bytes:
        """Remove and return every byte whose release time has come (nothing while stalled)."""
        out = bytearray()
        while self.releasable(now):
            out += self.out.popleft()[1]
        self.queued -= len(out)
        self.stats.bytes_out += len(out)
        return bytes(out)

    def discard(self) -> None:
        self.out.clear()
        self.queued = 0
        self.partial.clear()




def directions(seed: int, both: Optional[Faults], hub_to_device: Optional[Faults],
               device_to_hub: Optional[Faults]) -> Dict[str, Direction]:
    """The two directions of a link, ``h2d`` and ``d2h``, each with its own seeded RNG."""
    base = both or Faults()
    return {
        "h2d": Direction("h2d", replace(hub_to_device or base), random.Random(seed * 2 + 1)),
        "d2h": Direction("d2h", replace(device_to_hub or base), random.Random(seed * 2 + 2)),
    }


def select_directions(dirs: Dict[str, Direction], direction: str) -> List[Direction]:
    if direction == "both":
        return list(dirs.values())
    if direction not in dirs:
        raise ValueError("direction must be 'h2d', 'd2h' or 'both'")
    return [dirs[direction]]


def link_stats(dirs: Dict[str, Direction]) -> Dict[str, Any]:
    """Counters per direction (``h2d``, ``d2h``) and totals (``frames``, ``faults``)."""
    out: Dict[str, Any] = {}
    for name, d in dirs.items():
        s = asdict(d.stats)
        s["faults"] = d.stats.faults
        out[name] = s
    out["frames"] = out["h2d"]["frames"] + out["d2h"]["frames"]
    out["faults"] = out["h2d"]["faults"] + out["d2h"]["faults"]
    return out
