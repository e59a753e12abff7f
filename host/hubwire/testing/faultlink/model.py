"""The plan of the model-based exactly-once test: a seeded stream of *bursts*, each a run of 1..300
messages of one kind, in either direction, some of them under a fault (:mod:`.model_run` plays them
against the soak sketch and counts what became of every message).

Duplicate detection on both sides keys on 8-bit sequence numbers: the hub's transaction counter
numbers its ``R``, ``C``, ``J``, ``S`` and its events ``!``; the device's one counter numbers its
events, its own ``R``/``C`` to the hub and its mission updates ``M``. A message is dropped as a
duplicate when it carries the seq and id of the last one of its kind, so what matters is how many
messages of *other* kinds pass between two of one kind. Plain random lengths almost never land on
the counter's edges, so half the time the planner plays a *sandwich*: a burst of a target kind, a
filler burst of another kind exactly as long as needed for the target's next message to come 256
(or 128, 129, or one either side) seqs after its last one, and the target kind again.
"""
from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence, Tuple

__all__ = ["HUB_KINDS", "DEVICE_KINDS", "KINDS", "FAULTS", "Burst", "Planner", "MAX_BURST"]

#: messages numbered by the hub's transaction counter (one seq per message)
HUB_KINDS = ("read", "write", "chunk", "subscribe", "hub_event", "blob_write", "blob_read")
#: messages numbered by the device's transaction counter
DEVICE_KINDS = ("device_event", "device_write", "mission", "mission_cancel")
KINDS = HUB_KINDS + DEVICE_KINDS
#: the faults a burst may run under ("clean" most of the time; "cut" and "reboot" are events)
FAULTS = ("drop", "dup", "ber", "delay", "stall", "cut", "reboot")
MAX_BURST = 300
#: distances (in messages of the counter) between two messages of one kind the planner aims at:
#: the 8-bit wrap and one either side, and the half-way point where a signed 8-bit comparison flips
HUB_DISTANCES = (256, 256, 256, 256, 255, 257, 128)
DEVICE_DISTANCES = (256, 256, 129, 129, 128, 130, 255, 257)
#: kinds whose repetition the device (hub side) or the hub (device side) deduplicates
#: (a blob read's target is the hub's reassembly, which also keys on the seq)
HUB_TARGETS = ("hub_event", "write", "blob_write", "blob_read")
DEVICE_TARGETS = ("device_write", "mission", "device_event")
DEVICE_FILLERS = ("device_event", "device_write", "mission")


@dataclass
class Burst:
    kind: str
    n: int
    fault: str = "clean"
    aimed: str = ""  # "target@distance" when the length was aimed, for the log
    wait: bool = True  # device kinds: wait for the burst to end before the next one

    def __str__(self) -> str:
        extra = f" aimed {self.aimed}" if self.aimed else ""
        return f"{self.kind} x{self.n} [{self.fault}]{extra}"


class Planner:
    """Bursts from a seed. ``next`` takes where the counters stand now (``hub_seq``: the hub's
    counter; ``hub_last[kind]``: the seq of that kind's last message; ``device_count``: device
    messages seen so far; ``device_last[kind]``: the count at that kind's last message)."""

    def __init__(self, seed: int, fault_rate: float = 0.25, aim_rate: float = 0.5,
                 kinds: Tuple[str, ...] = KINDS) -> None:
        self.rng = random.Random(seed)
        self.fault_rate, self.aim_rate, self.kinds = fault_rate, aim_rate, kinds
        self.forced: List[Burst] = []
        #: a kind half the plain bursts play (the runner sets the one that sent the fewest messages)
        self.favour: Optional[str] = None
        self.log: List[str] = []

    def length(self) -> int:
        """1..MAX_BURST, a third of them on a counter's edges."""
        r = self.rng
        if r.random() < 1 / 3:
            return r.choice((1, 2, 127, 128, 129, 254, 255, 256, 257))
        return r.randint(1, MAX_BURST)

    def fault(self) -> str:
        r = self.rng
        if r.random() >= self.fault_rate:
            return "clean"
        return r.choices(FAULTS, weights=(4, 3, 3, 2, 2, 1, 1))[0]

    def next(self, hub_seq: int, hub_last: Dict[str, int], device_count: int,
             device_last: Dict[str, int]) -> Burst:
        if self.forced:
            b = self.forced.pop(0)
            if b.n < 0:
                b.n = self._aimed(b, hub_seq, hub_last, device_count, device_last)
        else:
            b = self._draw()
        self.log.append(str(b))
        return b

    def _draw(self) -> Burst:
        r = self.rng
        fault = self.fault()
        if fault != "clean" or r.random() >= self.aim_rate:
            kind = self.favour if self.favour and r.random() < 0.5 else r.choice(self.kinds)
            return Burst(kind, self.length(), fault, wait=r.random() < 0.7)
        # a sandwich: the target kind, a filler aimed at the counter's edges, the target again
        targets: Sequence[str]
        fillers: Sequence[str]
        dists: Sequence[int]
        if r.random() < 0.5:
            targets, fillers, dists = HUB_TARGETS, HUB_KINDS, HUB_DISTANCES
        else:
            targets, fillers, dists = DEVICE_TARGETS, DEVICE_FILLERS, DEVICE_DISTANCES
        target = r.choice([t for t in targets if t in self.kinds])
        filler = r.choice([k for k in fillers if k != target and k in self.kinds])
        dist = r.choice(dists)
        small = r.choice((1, 1, 2, 3, r.randint(1, MAX_BURST)))
        # the targets under byte drops now and then: a message lost or half received at the edge
        hit = "drop" if r.random() < 0.2 else "clean"
        self.forced = [Burst(filler, -1, aimed=f"{target}@{dist}"),
                       Burst(target, r.choice((1, 1, 2, 3)), hit, aimed=f"target@{dist}")]
        return Burst(target, small, hit)

    def _aimed(self, b: Burst, hub_seq: int, hub_last: Dict[str, int], device_count: int,
               device_last: Dict[str, int]) -> int:
        """The filler's length: the target's next message comes ``dist`` seqs after its last."""
        target, dist = b.aimed.split("@")
        if b.kind in HUB_KINDS and target in hub_last:
            # the filler takes seqs hub_seq+1 .. hub_seq+n, the target's next one hub_seq+n+1
            return (hub_last[target] + int(dist) - hub_seq - 1) % 256 or 256
        if b.kind not in HUB_KINDS and target in device_last:
            n = device_last[target] + int(dist) - device_count - 1
            if b.kind == "mission":  # the board sends the latest progress only: some never go out
                n += self.rng.randint(0, n // 8)
            if 1 <= n <= MAX_BURST:
                return n
        b.aimed += " (missed)"
        return self.length()
