"""Missions (PROTOCOL.md 11): the device's mission updates ``M`` acked, deduplicated and routed to
the run they belong to, in order; runs failed with :class:`MissionLost` when the board reboots, and
marked "link lost" while the link is down.

Starting and cancelling are ordinary controls (``C`` through :mod:`.transactions`, one at a time,
exactly once); this module keeps the runs the hub started. A :class:`MissionRun` is shared by the
synchronous :class:`hubwire.Job` and the asyncio job: the loop thread changes it, both faces wait
on it (a condition variable for threads, wakers for coroutines).
"""
from __future__ import annotations

import logging
import threading
from collections import deque
from typing import Any, Callable, Deque, Dict, List, Optional, Tuple

from ..descriptor import Channel
from ..errors import HubwireError, InvalidValue, MissionCancelled, MissionError, MissionFailed, MissionLost
from ..text import clip
from ..wire import messages as m
from ..wire.frame import Frame
from ..wire.missions import MissionKind, MissionUpdate

__all__ = ["Missions", "MissionRun", "FEEDBACK_LIMIT", "start_run_number"]

log = logging.getLogger("hubwire")

#: progress values a run keeps for its readers; beyond it the oldest are dropped (a reader that
#: falls this far behind skips them)
FEEDBACK_LIMIT = 4096


class MissionRun:
    """One run the hub started: ``channel``, device ``run`` number and the device ``nonce`` it runs
    under; ``progress`` values in arrival order (``dropped`` of them gone from the front), then the
    outcome: ``result`` or ``error``."""

    def __init__(self, channel: Channel, run: int, nonce: int) -> None:
        self.channel = channel
        self.run = run
        self.nonce = nonce
        self.progress: Deque[Any] = deque(maxlen=FEEDBACK_LIMIT)
        self.received = 0  # progress values received in all (index of the next one)
        self.final: Optional[str] = None
        self.result: Any = None
        self.error: Optional[MissionError] = None
        self.link_lost = False
        self.cond = threading.Condition()
        #: called on the loop after every change (the asyncio job's wake-up)
        self.wakers: List[Callable[[], None]] = []
        #: called through the session's dispatcher with the new status when it changes
        self.status_cbs: List[Callable[[str], Any]] = []

    @property
    def status(self) -> str:
        if self.final is not None:
            return self.final
        return "link lost" if self.link_lost else "running"

    @property
    def done(self) -> bool:
        return self.final is not None

    def dropped(self) -> int:
        return self.received - len(self.progress)

    def progress_from(self, index: int) -> Tuple[List[Any], int]:
        """Progress values from ``index`` on (skipping dropped ones) and the index after them."""
        with self.cond:
            start = max(index, self.dropped())
            items = list(self.progress)[start - self.dropped():]
            return items, start + len(items)

    def outcome(self) -> Any:
        """The result, or raise the run's error (only once :attr:`done`)."""
        if self.error is not None:
            raise self.error
        return self.result

    def describe(self) -> str:
        return f"mission {self.channel.name!r} run {self.run}"

    def changed(self, status: Optional[str], dispatch: Callable[..., Any]) -> None:
        """After a change (on the loop): wake both faces' waiters; with a new ``status``, hand it
        to the status callbacks through ``dispatch`` (where the application's callbacks run)."""
        with self.cond:
            self.cond.notify_all()
        for w in list(self.wakers):
            w()
        if status is not None:
            for cb in list(self.status_cbs):
                dispatch(cb, status)

    def end(self, status: str, error: Optional[MissionError], dispatch: Callable[..., Any]) -> None:
        """The outcome, once: a later one (a repeat, or a loss after the end) changes nothing."""
        with self.cond:
            if self.final is not None:
                return
            self.final, self.error = status, error
        self.changed(status, dispatch)


class Missions:
    """The missions of one session. ``core`` provides ``link``, ``stats``, ``dispatch`` and
    ``device_hello``. Runs are keyed by (channel id, run) and belong to one device nonce; an ended
    run stays until a run of the same number replaces it (at most 255 per channel)."""

    def __init__(self, core: Any) -> None:
        self.core = core
        self.lock = threading.Lock()
        self.runs: Dict[Tuple[int, int], MissionRun] = {}
        #: (device nonce, seq, id) of the last update delivered: a repeat is acked, not delivered
        self.last: Optional[Tuple[int, int, int]] = None
        #: channel id -> updates of runs not known yet, kept while a start of that channel is out
        #: (its answer and the run's first update may overtake the caller registering the run)
        self.early: Dict[int, List[Tuple[int, MissionUpdate]]] = {}

    # --------------------------------------------------------------------------- starting

    def expect(self, cid: int) -> None:
        """A start of channel ``cid`` is about to be sent."""
        with self.lock:
            self.early[cid] = []

    def unexpect(self, cid: int) -> None:
        with self.lock:
            self.early.pop(cid, None)

    def register(self, channel: Channel, run: int, nonce: int) -> MissionRun:
        """The run the device answered a start with; takes the updates that arrived before it."""
        rec = MissionRun(channel, run, nonce)
        h = self.core.device_hello
        with self.lock:  # held while the early updates are applied: a later one waits behind them
            early = self.early.pop(channel.id, [])
            old = self.runs.get((channel.id, run))
            if old is not None and not old.done:
                self._end(old, "lost", MissionLost(f"{old.describe()} was replaced by a new run of that number",
                                                   channel.name, run))
            self.runs[(channel.id, run)] = rec
            if h is None or h.nonce != nonce:
                self._end(rec, "lost", MissionLost(f"{rec.describe()}: the board rebooted while the mission ran",
                                                   channel.name, run))
            for n, u in early:
                if n == nonce and u.run == run:
                    self._apply(rec, u)
        return rec

    # --------------------------------------------------------------------------- updates

    def on_update(self, f: Frame) -> None:
        """An ``M`` from the device: ack it, deliver it once to its run (or ignore it)."""
        core = self.core
        h = core.device_hello
        core.link.send_frame(m.ACK, f.seq, f.id)
        nonce = h.nonce if h is not None else 0
        key = (nonce, f.seq, f.id)
        if self.last == key:
            core.stats.duplicate_mission_updates += 1
            return
        self.last = key
        core.stats.mission_updates += 1
        try:
            u = MissionUpdate.unpack(f.payload)
        except m.PayloadError as e:
            log.warning("hubwire: malformed mission update on channel id %d: %s", f.id, clip(str(e), 160))
            return
        with self.lock:  # against register() on a caller's thread
            rec = self.runs.get((f.id, u.run))
            if rec is None or rec.nonce != nonce or rec.done:
                if f.id in self.early:
                    self.early[f.id].append((nonce, u))
                else:
                    core.stats.unknown_mission_updates += 1
                return
            self._apply(rec, u)

    def _apply(self, rec: MissionRun, u: MissionUpdate) -> None:
        ch = rec.channel
        try:
            if u.kind == MissionKind.PROGRESS:
                value = (ch.progress.decode(u.data) if ch.progress is not None else None)
                with rec.cond:
                    rec.progress.append(value)
                    rec.received += 1
                self._changed(rec, None)
            elif u.kind == MissionKind.SUCCEEDED:
                rec.result = ch.returns.decode(u.data) if ch.returns is not None else None
                self._end(rec, "succeeded", None)
            elif u.kind == MissionKind.FAILED:
                self._end(rec, "failed", MissionFailed(ch.name, rec.run, u.code))
            else:
                self._end(rec, "cancelled", MissionCancelled(ch.name, rec.run))
        except InvalidValue as e:
            log.warning("hubwire: %s: malformed update: %s", rec.describe(), clip(str(e), 160))
            if u.final:  # the outcome is lost with it: say so rather than wait for ever
                self._end(rec, "failed", MissionError(f"{rec.describe()} ended with a malformed update: {e}",
                                                      ch.name, rec.run))

    def _end(self, rec: MissionRun, status: str, error: Optional[MissionError]) -> None:
        rec.end(status, error, self.core.dispatch)

    def _changed(self, rec: MissionRun, status: Optional[str]) -> None:
        rec.changed(status, self.core.dispatch)

    # ------------------------------------------------------------------------------ link

    def _live(self) -> List[MissionRun]:
        with self.lock:
            return [r for r in self.runs.values() if not r.done]

    def link_down(self) -> None:
        """The link is lost: runs go on on the board; their status says so until it is back."""
        for rec in self._live():
            if not rec.link_lost:
                rec.link_lost = True
                self._changed(rec, "link lost")

    def restored(self, nonce: int) -> None:
        """The link is back with the board session ``nonce``: its runs are running again."""
        for rec in self._live():
            if rec.nonce == nonce and rec.link_lost:
                rec.link_lost = False
                self._changed(rec, "running")

    def rebooted(self) -> None:
        """The board rebooted (a new nonce, or new firmware): no run of the earlier boot can end."""
        for rec in self._live():
            self._end(rec, "lost", MissionLost(f"{rec.describe()}: the board rebooted while the mission ran",
                                                   rec.channel.name, rec.run))

    def close(self) -> None:
        for rec in self._live():
            self._end(rec, "lost", MissionLost(f"{rec.describe()}: the session was closed while the mission ran",
                                               rec.channel.name, rec.run))


def start_run_number(answer: Frame, name: str) -> int:
    """The run number of the device's answer to a start (an ``r`` of one byte)."""
    if answer.type != m.RESPONSE or len(answer.payload) != 1 or answer.payload[0] == 0:
        raise HubwireError(f"the device answered a start of mission {name!r} with "
                           f"{m.TYPE_NAMES.get(answer.type, hex(answer.type))} {answer.payload.hex() or '(empty)'} "
                           "instead of a run number: is it a mission?")
    return answer.payload[0]
