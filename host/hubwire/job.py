"""Missions on the faces: :class:`Job` (``dev.start`` of the synchronous :class:`hubwire.Device`) and
:class:`AsyncJob` (``await adev.start`` of :class:`hubwire.aio.AsyncDevice`), both over one
:class:`hubwire.session.missions.MissionRun` that the session's loop keeps up to date.

A start and a cancel are ordinary controls (``C``, exactly once, one at a time); the run's progress,
result, failure or cancellation arrive as mission updates (PROTOCOL.md 11)."""
from __future__ import annotations

import asyncio
import time
from typing import Any, AsyncIterator, Callable, Iterator, Optional

from . import ops
from .errors import Timeout
from .session.missions import MissionRun, start_run_number
from .wire import messages as m
from .wire.frame import Frame
from .wire.missions import cancel_payload

__all__ = ["Job", "AsyncJob", "start_job", "start_async_job"]


def _cancelled(answer: Frame) -> bool:
    """The device's answer to a cancel: ``r`` 1 when the run was running (PROTOCOL.md 11.2)."""
    return answer.type == m.RESPONSE and answer.payload[:1] == b"\x01"


class _JobBase:
    _rec: MissionRun

    @property
    def mission(self) -> str:
        """The mission channel's name."""
        return self._rec.channel.name

    @property
    def run(self) -> int:
        """The device's run number (1..255, per mission channel since the board booted)."""
        return self._rec.run

    @property
    def status(self) -> str:
        """``"running"``, ``"link lost"`` (the run goes on on the board; its updates wait for the
        link), ``"succeeded"``, ``"failed"``, ``"cancelled"`` or ``"lost"`` (the board rebooted)."""
        return self._rec.status

    def done(self) -> bool:
        """True once the run has ended (its outcome is known, or lost)."""
        return self._rec.done

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.mission} run {self.run} ({self.status})>"


class Job(_JobBase):
    """A mission run started with :meth:`hubwire.Device.start`::

        job = dev.start("drive", 2.0)
        for metres in job.feedback():
            print(metres)
        print(job.result(timeout=30))
    """

    def __init__(self, session: Any, rec: MissionRun) -> None:
        self._session = session
        self._rec = rec

    def feedback(self, timeout: Optional[float] = None) -> Iterator[Any]:
        """The run's progress values in the order the board reported them, from the start of the
        run; ends when the run ends (then :meth:`result` tells how). :class:`Timeout` after
        ``timeout`` s without an update (None: no limit)."""
        rec = self._rec
        index = 0
        while True:
            items, index = rec.progress_from(index)
            yield from items
            with rec.cond:
                if rec.received > index:
                    continue
                if rec.done:
                    return
                if not rec.cond.wait(timeout) and rec.received <= index and not rec.done:
                    raise Timeout(f"no progress of {rec.describe()} within {timeout:g} s")

    def result(self, timeout: Optional[float] = None) -> Any:
        """The run's result once it succeeded; raises :class:`MissionFailed` (``.code``),
        :class:`MissionCancelled`, :class:`MissionLost` (the board rebooted) or :class:`Timeout`."""
        rec = self._rec
        with rec.cond:
            if not rec.cond.wait_for(lambda: rec.done, timeout):
                raise Timeout(f"{rec.describe()} did not end within {timeout:g} s (status {rec.status})")
        return rec.outcome()

    def cancel(self, *, timeout: Optional[float] = None) -> bool:
        """Ask the board to cancel the run. True when it was running (its cancel function was
        called; :meth:`result` then raises :class:`MissionCancelled` unless the sketch finished it
        first); False when it had already ended."""
        rec = self._rec
        if rec.done:
            return False
        return _cancelled(self._session.control(rec.channel.id, cancel_payload(rec.run), timeout=timeout,
                                                what=f"cancel of {rec.describe()}"))

    def on_status(self, callback: Callable[[str], Any]) -> Callable[[], None]:
        """Call ``callback(status)`` (on the dispatcher thread) when the status changes: link lost,
        running again, or the end. Returns a function removing it."""
        cbs = self._rec.status_cbs
        cbs.append(callback)
        return lambda: cbs.remove(callback) if callback in cbs else None


def start_job(session: Any, name: str, goal: Any, timeout: Optional[float]) -> Job:
    """Start mission ``name`` on a synchronous session; the :class:`Job` once the run number is known."""
    ch, payload = ops.mission_start(session.descriptor, name, goal)  # a non-mission or a bad goal first
    if getattr(session, "remote", None) is not None:  # through hubwire serve: the service owns the run
        return session.start_mission(name, goal, timeout)  # type: ignore[no-any-return]
    missions = session.core.missions
    missions.expect(ch.id)
    try:
        answer = session.control(ch.id, payload, timeout=timeout, what=name)
        h = session.core.device_hello
        return Job(session, missions.register(ch, start_run_number(answer, name), h.nonce if h else 0))
    finally:
        missions.unexpect(ch.id)


class AsyncJob(_JobBase):
    """A mission run started with :meth:`hubwire.aio.AsyncDevice.start`::

        job = await dev.start("drive", 2.0)
        async for metres in job.feedback():
            print(metres)
        print(await job.result(timeout=30))
    """

    def __init__(self, core: Any, rec: MissionRun) -> None:
        self._core = core
        self._rec = rec

    async def _change(self, timeout: Optional[float], what: str) -> None:
        """Wait for the run's next change (Timeout after ``timeout`` s)."""
        fut = self._core.loop.create_future()

        def wake() -> None:
            if not fut.done():
                fut.set_result(None)
        self._rec.wakers.append(wake)
        try:
            await asyncio.wait_for(fut, timeout)
        except asyncio.TimeoutError:
            raise Timeout(f"{what} of {self._rec.describe()} within {timeout:g} s") from None
        finally:
            self._rec.wakers.remove(wake)

    async def feedback(self, timeout: Optional[float] = None) -> AsyncIterator[Any]:
        """``async for``: the progress values in order, from the start of the run, until it ends."""
        rec = self._rec
        index = 0
        while True:
            items, index = rec.progress_from(index)
            for item in items:
                yield item
            if rec.received > index:
                continue
            if rec.done:
                return
            end = None if timeout is None else time.monotonic() + timeout
            await self._change(None if end is None else max(0.0, end - time.monotonic()), "no progress")

    async def result(self, timeout: Optional[float] = None) -> Any:
        """As :meth:`Job.result`."""
        end = None if timeout is None else time.monotonic() + timeout
        while not self._rec.done:
            await self._change(None if end is None else max(0.0, end - time.monotonic()), "no end")
        return self._rec.outcome()

    async def cancel(self, *, timeout: Optional[float] = None) -> bool:
        """As :meth:`Job.cancel`."""
        rec = self._rec
        if rec.done:
            return False
        return _cancelled(await self._core.tx.transact(m.CONTROL, rec.channel.id, cancel_payload(rec.run),
                                                       timeout=timeout, what=f"cancel of {rec.describe()}"))

    def on_status(self, callback: Callable[[str], Any]) -> Callable[[], None]:
        """As :meth:`Job.on_status`, the callback running on the loop."""
        cbs = self._rec.status_cbs
        cbs.append(callback)
        return lambda: cbs.remove(callback) if callback in cbs else None


async def start_async_job(core: Any, name: str, goal: Any, timeout: Optional[float]) -> AsyncJob:
    """Start mission ``name`` on a session core (the asyncio face)."""
    ch, payload = ops.mission_start(core.descriptor, name, goal)
    core.missions.expect(ch.id)
    try:
        answer = await core.tx.transact(m.CONTROL, ch.id, payload, timeout=timeout, what=name)
        h = core.device_hello
        return AsyncJob(core, core.missions.register(ch, start_run_number(answer, name), h.nonce if h else 0))
    finally:
        core.missions.unexpect(ch.id)
