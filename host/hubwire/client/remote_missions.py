"""Missions through ``hubwire serve`` on the client side: a run the service owns, followed over the
socket (``mission`` subscription, docs/SERVICE.md "Missions") into a local
:class:`hubwire.session.missions.MissionRun`, so the jobs here are the direct :class:`hubwire.Job`
and :class:`hubwire.job.AsyncJob` with only ``cancel`` going through the service.

The service sends each progress value with its index, in order, and the outcome once; a client that
loses the service (or closes) ends its job as lost, while the run goes on with the service:
``follow(run_id)`` picks it up again, from its first progress value.
"""
from __future__ import annotations

import asyncio
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional, cast

from .. import ops
from ..errors import MissionCancelled, MissionError, MissionFailed, MissionLost
from ..job import AsyncJob, Job
from ..session.missions import MissionRun
from .protocol import raise_error

if TYPE_CHECKING:
    from ..descriptor import Descriptor
    from .connection import AsyncRemoteDevice, Connection

__all__ = ["RunFeed", "AsyncRemoteJob", "RemoteJob", "RemoteMissions", "follow_run", "outcome_error"]

Dispatch = Callable[..., Any]


def _on_loop(cb: Callable[..., Any], *args: Any) -> None:
    res = cb(*args)
    if asyncio.iscoroutine(res):
        asyncio.get_running_loop().create_task(res)


def outcome_error(o: Dict[str, Any], mission: str, run: int) -> Optional[MissionError]:
    """The error an outcome (``result`` push) stands for; None for a success."""
    status = o.get("status")
    if status == "succeeded":
        return None
    if status == "failed" and isinstance(o.get("code"), int):
        return MissionFailed(mission, run, int(o["code"]))
    if status == "cancelled":
        return MissionCancelled(mission, run)
    text = str(o.get("message", f"mission {mission!r} run {run} ended {status}"))
    return MissionLost(text, mission, run) if status == "lost" else MissionError(text, mission, run)


class RunFeed:
    """Applies the service's pushes for one run to a local :class:`MissionRun` (on the loop)."""

    def __init__(self, dev: "AsyncRemoteDevice", dispatch: Dispatch) -> None:
        self.dev = dev
        self.dispatch = dispatch
        self.rec: Optional[MissionRun] = None
        self.early: List[Dict[str, Any]] = []  # pushes before the answer named the run

    def begin(self, run: Dict[str, Any]) -> MissionRun:
        self.rec = MissionRun(self.dev.channel(str(run["mission"])), int(run["run"]), 0)
        early, self.early = self.early, []
        for msg in early:
            self.push(msg)
        return self.rec

    def push(self, msg: Dict[str, Any]) -> None:
        rec = self.rec
        if rec is None:
            self.early.append(msg)
            return
        if rec.done:
            return
        if "progress" in msg:
            p = msg["progress"]
            ch = rec.channel
            value = ch.progress.decode(bytes.fromhex(str(p["raw"]))) if ch.progress is not None else None
            with rec.cond:
                rec.received = max(rec.received, int(p["index"]))  # values the service no longer kept
                rec.progress.append(value)
                rec.received += 1
            self._changed(rec, None)
        elif "status" in msg:
            rec.link_lost = msg["status"] == "link lost"
            self._changed(rec, rec.status)
        elif "result" in msg:
            o = msg["result"]
            err = outcome_error(o, rec.channel.name, rec.run)
            ret = rec.channel.returns
            if err is None and ret is not None and o.get("raw") is not None:
                rec.result = ret.decode(bytes.fromhex(str(o["raw"])))
            self._end(rec, str(o.get("status")), err)
        elif "end" in msg:  # the connection to the service is gone; the run is not
            self._end(rec, "lost", MissionLost(
                f"{rec.describe()}: {msg.get('message', 'the service went away')}; the run itself goes on with "
                "hubwire serve (follow it again by its run id)", rec.channel.name, rec.run))

    def _end(self, rec: MissionRun, status: str, error: Optional[MissionError]) -> None:
        rec.end(status, error, self.dispatch)

    def _changed(self, rec: MissionRun, status: Optional[str]) -> None:
        rec.changed(status, self.dispatch)


async def follow_run(dev: "AsyncRemoteDevice", run_id: str, dispatch: Dispatch = _on_loop) -> "tuple[MissionRun, str]":
    """Follow the service's run ``run_id`` from its first progress value: the local record of it."""
    feed = RunFeed(dev, dispatch)

    def push(msg: Dict[str, Any]) -> None:
        feed.push(msg)
        if "result" in msg:  # the service ended the subscription with it: forget it here too
            dev.conn._subs.pop(sub, None)
            if sub in dev._subs:
                dev._subs.remove(sub)
    sub, fut = dev.conn.subscribe_nowait("mission", push, run_id=run_id)
    msg = await fut
    if not msg.get("ok"):
        dev.conn._subs.pop(sub, None)
        raise_error(msg)
    if sub in dev.conn._subs:
        dev._subs.append(sub)
    return feed.begin(msg["run"]), str(msg["run"]["run_id"])


class AsyncRemoteJob(AsyncJob):
    """:class:`hubwire.job.AsyncJob` of a run the service owns; ``run_id`` names it there."""

    def __init__(self, dev: "AsyncRemoteDevice", rec: MissionRun, run_id: str) -> None:
        super().__init__(SimpleNamespace(loop=asyncio.get_running_loop()), rec)
        self._dev = dev
        self.run_id = run_id

    async def cancel(self, *, timeout: Optional[float] = None) -> bool:
        if self._rec.done:
            return False
        return await self._dev.cancel_run(self.run_id, timeout=timeout)


class RemoteJob(Job):
    """:class:`hubwire.Job` of a run the service owns (``dev.start`` through ``hubwire serve``)."""

    def __init__(self, session: Any, rec: MissionRun, run_id: str) -> None:
        super().__init__(session, rec)
        self.run_id = run_id

    def cancel(self, *, timeout: Optional[float] = None) -> bool:
        if self._rec.done:
            return False
        return bool(self._session._run(self._session.remote.cancel_run(self.run_id, timeout=timeout)))


class RemoteMissions:
    """The mission members of :class:`AsyncRemoteDevice` (``conn``, ``key`` and ``_desc`` are its)."""

    conn: "Connection"
    key: str
    _desc: "Descriptor"

    async def start_run(self, name: str, goal: Any = None, *, timeout: Optional[float] = None,
                        run_id: Optional[str] = None, dispatch: Any = None) -> "tuple[Any, str]":
        """Start mission ``name`` through the service (goal checked here first, as direct) and
        follow the run: its local record and run id."""
        ch, payload = ops.mission_start(self._desc, name, goal)
        extra = {} if run_id is None else {"run_id": run_id}
        reply = await self.conn.request("start", board=self.key, channel=ch.name, raw=payload[1:].hex(),
                                        timeout=timeout, **extra)
        rid = str(reply["run"]["run_id"])
        return await (follow_run(cast("AsyncRemoteDevice", self), rid) if dispatch is None else follow_run(cast("AsyncRemoteDevice", self), rid, dispatch))

    async def start(self, name: str, goal: Any = None, *, timeout: Optional[float] = None,
                    run_id: Optional[str] = None) -> Any:
        """As :meth:`AsyncDevice.start`; the run belongs to the service (``job.run_id`` names it
        there: a start repeated with the same ``run_id`` starts nothing new)."""
        rec, rid = await self.start_run(name, goal, timeout=timeout, run_id=run_id)
        return AsyncRemoteJob(cast("AsyncRemoteDevice", self), rec, rid)

    async def follow(self, run_id: str) -> Any:
        """The job of a run the service has (started by any client), from its first progress value."""
        rec, rid = await follow_run(cast("AsyncRemoteDevice", self), run_id)
        return AsyncRemoteJob(cast("AsyncRemoteDevice", self), rec, rid)

    async def cancel_run(self, run_id: str, *, timeout: Optional[float] = None) -> bool:
        return bool((await self.conn.request("cancel", run_id=run_id, timeout=timeout))["cancelled"])

    async def runs(self) -> List[Dict[str, Any]]:
        """The runs the service keeps of this board (docs/SERVICE.md "Missions")."""
        return list((await self.conn.request("runs", board=self.key))["runs"])
