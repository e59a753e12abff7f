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
- for every kind: a (seq, id) still in flight (``busy``), so an answer never meets the wrong message.

A rebooted device remembers nothing: both sets are emptied. A hub that resumes its session after
its own restart (:mod:`.resume`) starts with both filled from what it stored.

Not thread-safe: the caller holds its lock (:class:`.transactions.Transactions`).
"""
from __future__ import annotations

from typing import Callable, Dict, Optional, Set

from ..wire import messages as m

__all__ = ["SeqRules"]


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

    def draw(self, type: int, id: int, busy: Callable[[int, int], bool]) -> Optional[int]:
        """The next free seq for a new ``type`` message to ``id``; None when all 256 are taken."""
        avoid: "Dict[int, int] | Set[int]" = (self.controls if type == m.CONTROL
                                              else self.events if type == m.EVENT else set())
        seq = self.seq
        for _ in range(256):
            seq = (seq + 1) & 0xFF
            if seq not in avoid and not busy(seq, id):
                self.seq = seq
                self.draws += 1
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
        self.controls = {}
        self.events = set()
        self._acked = None
