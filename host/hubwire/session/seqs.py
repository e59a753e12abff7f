"""Which seq a new hub message carries (PROTOCOL.md 4.1): the hub's one 8-bit transaction counter,
skipping every value the device might take for something else.

The device keeps two duplicate memories of the hub's frames (4.4, 10.3): the last hub ``C`` (seq, id)
as long as no other hub ``R``/``C``/``J``/``S`` came after it, and the (seq, id) of the last hub event
``!`` it delivered. A new message of either stream with a seq the device may still remember would
be taken for a retry: answered, not applied. The counter wraps every 256 messages of all kinds, so
counting alone does not prevent it; :class:`SeqRules` skips:

- for a ``C``: the seq of the last control answered (ACK or ``r``) and of every control since that
  ended unanswered or with a NAK (the device may have applied any of them), until an answer to an
  ``R``, ``J`` or ``S`` drawn after they ended (anything but NAK ``NOT_LINKED``) proves the device
  has handled another transaction since;
- for a ``!``: the seq of the last event acknowledged and of the previous event;
- for every kind: a (seq, id) still in flight (``busy``), and one whose answer may still come
  (:class:`Unanswered`), so an answer never meets the wrong message.

A rebooted device remembers nothing: both sets are emptied. A hub that resumes its session after
its own restart (:mod:`.resume`) starts with both filled from what it stored.

Not thread-safe: the caller holds its lock (:class:`.transactions.Transactions`).
"""
from __future__ import annotations

from collections import deque
from typing import Callable, Deque, Dict, Optional, Set, Tuple

from ..wire import messages as m

__all__ = ["SeqRules", "Unanswered"]

Key = Tuple[int, int]


class Unanswered:
    """The (seq, id) of hub messages whose answer may still come (PROTOCOL.md 4.1 rule 3).

    A message the hub gave up on (a timeout, a read retried under a new seq) may be answered much
    later: a device blocked in its ``loop()`` answers what sits in its receive buffer when it runs
    again, however many seqs the hub drew meanwhile. The line keeps order and the device answers in
    the order it receives, so an answer to a message means that everything sent before that message
    was answered or lost. Each (seq, id) is kept from its draw until an answer arrives to a message
    drawn after it ended (or the device's hello answers a hub hello sent after it ended); until then
    no new message takes it. At most one entry per (seq, id): 65,536, reached only by a device that
    answers nothing while the hub keeps drawing; a channel whose 256 seqs are all kept gets no new
    message (the caller probes the device) until an answer comes.
    """

    def __init__(self) -> None:
        #: a clock of draws and ends: orders them against each other
        self.tick = 0
        #: (seq, id) -> tick it was drawn at
        self.drawn: Dict[Key, int] = {}
        #: (tick it ended, key), in the order they ended: what an answer may forget
        self._ended: Deque[Tuple[int, Key]] = deque()
        self._done: Set[Key] = set()  # keys in _ended (ended once per draw)

    def __contains__(self, key: object) -> bool:
        return key in self.drawn

    def __len__(self) -> int:
        return len(self.drawn)

    def now(self) -> int:
        self.tick += 1
        return self.tick

    def add(self, key: Key) -> None:
        self.drawn[key] = self.now()

    def ended(self, key: Key) -> None:
        """No copy of ``key`` is sent any more (answered, given up, or sent under a new seq)."""
        if key in self.drawn and key not in self._done:
            self._done.add(key)
            self._ended.append((self.now(), key))

    def answered(self, key: Key) -> None:
        """An answer to ``key`` arrived: everything that ended before it was drawn has had its answer."""
        at = self.drawn.get(key)
        if at is not None:
            self.answered_through(at)

    def answered_through(self, tick: int) -> None:
        """Every message that ended before ``tick`` has been answered or lost."""
        while self._ended and self._ended[0][0] < tick:
            _, key = self._ended.popleft()
            self._done.discard(key)
            del self.drawn[key]

    def forget_ended(self) -> None:
        """A rebooted device answers nothing it received before: only what is still in flight stays."""
        for _, key in self._ended:
            del self.drawn[key]
        self._ended.clear()
        self._done.clear()


class SeqRules:
    """The hub's transaction counter and what it must skip; ``start``: its first value minus one."""

    def __init__(self, start: int) -> None:
        self.seq = start & 0xFF
        #: how many seqs were drawn so far: orders draws and the ends of controls
        self.draws = 0
        #: seq -> draws when it ended: controls the device may remember (4.4)
        self.controls: Dict[int, int] = {}
        #: seqs of the last hub event acknowledged and of the last one ended (10.3)
        self.events: Set[int] = set()
        self._acked: Optional[int] = None
        #: (seq, id) whose answer may still come: skipped for every kind
        self.unanswered = Unanswered()

    def draw(self, type: int, id: int, busy: Callable[[int, int], bool]) -> Optional[int]:
        """The next free seq for a new ``type`` message to ``id``; None when all 256 are taken."""
        avoid: "Dict[int, int] | Set[int]" = (self.controls if type == m.CONTROL
                                              else self.events if type == m.EVENT else set())
        seq = self.seq
        for _ in range(256):
            seq = (seq + 1) & 0xFF
            if seq not in avoid and not busy(seq, id) and (seq, id) not in self.unanswered:
                self.seq = seq
                self.draws += 1
                self.unanswered.add((seq, id))
                return seq
        return None

    def control_answered(self, seq: int) -> None:
        """A ``C`` was answered ACK or ``r``: the device remembers it, and no earlier control."""
        self.controls = {seq: self.draws}

    def control_ended(self, seq: int) -> None:
        """A ``C`` ended unanswered or with a NAK: the device may remember it (or still an earlier one)."""
        self.controls[seq] = self.draws

    def other_answered(self, drawn: int) -> None:
        """An ``R``, ``J`` or ``S`` drawn as draw number ``drawn`` was answered (not NAK NOT_LINKED): the
        device handled it after every control that had ended by then, so it remembers none of them."""
        if self.controls:
            self.controls = {s: at for s, at in self.controls.items() if at >= drawn}

    def event_ended(self, seq: int, acked: bool) -> None:
        """A hub event was answered: ACK (the device remembers it) or NAK (it did not deliver it)."""
        if acked:
            self._acked = seq
        self.events = {seq} if self._acked is None else {seq, self._acked}

    def resumed(self, acked: Optional[int], head: Optional[int]) -> None:
        """An earlier run of the hub used this hub nonce with the device (:mod:`.resume`): skip the
        seqs of its last event acknowledged and of the one in flight, and take every seq for a
        control the device may remember, until an ``R``, ``J`` or ``S`` drawn from now on is answered."""
        self.controls = {s: self.draws for s in range(256)}
        self._acked = acked
        self.events = {s for s in (acked, head) if s is not None}

    def device_rebooted(self) -> None:
        """A new device session remembers nothing of the hub's frames."""
        self.unanswered.forget_ended()
        self.controls = {}
        self.events = set()
        self._acked = None
