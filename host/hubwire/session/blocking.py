"""Transactions driven by the calling thread (the synchronous API).

The caller registers its transaction, writes the frame itself and sleeps on the transaction's
event; the event loop matches the answer and wakes it. A round trip costs one thread hand-over,
as a dedicated reader thread would, instead of two through the loop. Retries, NOT_LINKED and the
stop-and-wait gate behave exactly as in :meth:`Transactions.transact`, and so does the bound on
transactions in flight: beyond it the caller sleeps until a slot is handed to it.
"""
from __future__ import annotations

import threading
import time
from contextlib import contextmanager
from typing import Any, Iterator, Optional

from ..errors import NakError
from ..wire import messages as m
from ..wire.frame import Frame
from .pending import GateCounts, Pending
from .transactions import no_seq

__all__ = ["ThreadGate", "transact", "wait_ready"]


class ThreadGate(GateCounts):
    """The stop-and-wait gate (:class:`GateCounts`) for threads (the synchronous API)."""

    def __init__(self) -> None:
        super().__init__()
        self._cv = threading.Condition()

    @contextmanager
    def shared(self) -> Iterator[None]:
        with self._cv:
            while not self._may_share():
                self._cv.wait()
            self._shared += 1
        try:
            yield
        finally:
            with self._cv:
                self._shared -= 1
                self._cv.notify_all()

    @contextmanager
    def exclusive(self) -> Iterator[None]:
        with self._cv:
            self._excl_waiting += 1
            try:
                while not self._may_own():
                    self._cv.wait()
            finally:
                self._excl_waiting -= 1
            self._excl = True
        try:
            yield
        finally:
            with self._cv:
                self._excl = False
                self._cv.notify_all()


def wait_ready(core: Any, timeout: float) -> None:
    """Return once READY; LinkLost / HubwireError at once if lost / closed, Timeout if still
    connecting after ``timeout`` s (woken by the core's state changes)."""
    deadline = time.monotonic() + timeout
    with core.sync_cv:
        while not core.ready_by(deadline):
            core.sync_cv.wait(deadline - time.monotonic())


def transact(core: Any, gate: ThreadGate, type: int, id: int, payload: bytes = b"", *,
             timeout: Optional[float] = None, what: str = "", tries: Optional[int] = None) -> Frame:
    """Send one transaction from this thread and return its answer; see :meth:`Transactions.transact`."""
    tx = core.tx
    retry = core.retry_timeout if timeout is None else timeout / core.tries
    with gate.exclusive() if type == m.CONTROL else gate.shared():
        wait_ready(core, max(core.connect_timeout, retry * core.tries))
        if type == m.CONTROL:
            with core.sync_cv:  # the hub's bind report is out: a round trip at most
                while not tx.claim_control("user"):
                    core.sync_cv.wait(retry)
        try:
            p = tx.try_register(type, id, payload, threaded=True, slot=True)
            if p is None:
                p = _register_later(core, type, id, payload, retry, what)
            p.max_tries = tries or 0
            try:
                tx.transmit(p)
                return _answer(core, p, retry, what)
            finally:
                tx.unregister(p)
        finally:
            if type == m.CONTROL:
                tx.release_control()


def _register_later(core: Any, type: int, id: int, payload: bytes, retry: float, what: str) -> Pending:
    """Wait for a slot; a ``C`` that finds every seq possibly remembered by the device reads the
    board id first (its answer ends that memory, PROTOCOL.md 4.4)."""
    tx = core.tx
    tx.wait_turn_thread()
    p: Optional[Pending] = tx.try_register(type, id, payload, threaded=True, slot=True, granted=True)
    if p is None:
        probe = tx.register(m.REQUEST, 0, b"", threaded=True)
        try:
            tx.transmit(probe)
            _answer(core, probe, retry, what)
        except NakError:
            pass  # a board without an id: refused after it was taken in, as good
        finally:
            tx.unregister(probe)
        tx.wait_turn_thread()
        p = tx.try_register(type, id, payload, threaded=True, slot=True, granted=True)
        if p is None:
            raise no_seq(type, what, core.url)
    return p


def _answer(core: Any, p: Pending, retry: float, what: str) -> Frame:
    tx = core.tx
    event = p.event
    assert event is not None
    while True:
        event.wait(max(0.0, p.sent_at + retry - time.monotonic()))
        if p.error is not None:
            raise p.error
        if p.answer is None:
            tx.silence(p, what)
            continue
        a: Optional[Frame] = tx.verdict(p, p.answer, what)
        if a is not None:
            return a
        # the device re-links on our hello; ask again (it was not applied) once it answered
        count = core.link.hello_count
        p.rearm()
        end = time.monotonic() + retry
        with core.sync_cv:
            while core.link.hello_count == count and p.error is None and time.monotonic() < end:
                core.sync_cv.wait(end - time.monotonic())
        if p.error is not None:
            raise p.error
        tx.retry(p)
