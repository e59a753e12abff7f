"""The client protocol's mission requests (docs/SERVICE.md "Missions"): ``start``, ``mission`` (follow
a run: its progress in order, its status, its outcome once), ``cancel`` and ``runs``, over the
service's table of runs (:mod:`.mission_runs`)."""
from __future__ import annotations

import asyncio
from typing import Any, Dict, Optional

from .. import ops
from ..errors import InvalidValue, LinkLost, MissionFailed
from ..wire.messages import NakCode
from .mission_runs import RunEntry, check_run_id, runs_of
from ..client.protocol import Usage, error_json, jsonable

__all__ = ["start", "follow", "cancel", "runs", "run_json", "outcome_json", "progress_json", "wait_change"]


def run_json(e: RunEntry) -> Dict[str, Any]:
    """A run as the protocol shows it."""
    job = e.job
    out: Dict[str, Any] = {"run_id": e.run_id, "board": e.key, "mission": e.mission, "status": e.status,
                           "run": job.run if job is not None else None,
                           "received": job._rec.received if job is not None else 0}
    return out


def progress_json(ch: Any, index: int, value: Any) -> Dict[str, Any]:
    raw = ch.progress.encode(value).hex() if ch.progress is not None else ""
    return {"index": index, "value": jsonable(value), "raw": raw}


def outcome_json(e: RunEntry) -> Dict[str, Any]:
    """How an ended run ended: ``status`` and the result, or the error (``code`` for a failure)."""
    if e.refused is not None:
        return {"status": "refused", **{k: v for k, v in error_json(e.refused).items() if k != "ok"}}
    rec = e.job._rec
    if rec.error is None:
        ret = rec.channel.returns
        raw = ret.encode(rec.result).hex() if ret is not None and rec.result is not None else None
        return {"status": rec.status, "value": jsonable(rec.result), "raw": raw}
    out: Dict[str, Any] = {"status": rec.status, "error": type(rec.error).__name__, "message": str(rec.error)}
    if isinstance(rec.error, MissionFailed):
        out["code"] = rec.error.code
    return out


def _goal(ch: Any, msg: Dict[str, Any]) -> Any:
    if "raw" in msg:
        try:
            return ch.codec.decode(bytes.fromhex(str(msg["raw"])))
        except ValueError as e:
            if isinstance(e, InvalidValue):
                raise
            raise InvalidValue(f"raw must be hex digits, not {str(msg['raw'])[:40]!r}", NakCode.BAD_VALUE) from None
    return msg.get("goal")


async def start(client: Any, msg: Dict[str, Any]) -> Dict[str, Any]:
    b = client.fleet.resolve(str(msg.get("board", "")))
    if b.device is None:
        raise LinkLost(f"board {b.key} is unplugged (last seen on {b.last_port}): nothing was sent")
    ch = b.device.channel(str(msg.get("channel")))
    if not ch.mission:  # a wrong request, not a refused start: nothing kept under a run id
        ops.mission_start(b.device.descriptor, ch.name, None)
    run_id = msg.get("run_id")
    e = await runs_of(client.fleet).start(client.fleet, b.key, ch.name, _goal(ch, msg),
                                          None if run_id is None else check_run_id(run_id), timeout_of(msg))
    return {"run": run_json(e)}


async def cancel(client: Any, msg: Dict[str, Any]) -> Dict[str, Any]:
    e = runs_of(client.fleet).get(msg.get("run_id"))
    if e.job is None or e.done:
        return {"cancelled": False}
    return {"cancelled": bool(await e.job.cancel(timeout=timeout_of(msg)))}


async def runs(client: Any, msg: Dict[str, Any]) -> Dict[str, Any]:
    board = msg.get("board")
    key = client.fleet.resolve(str(board)).key if board is not None else None
    return {"runs": [run_json(e) for e in runs_of(client.fleet).of_board(key)]}


async def follow(client: Any, msg: Dict[str, Any]) -> Dict[str, Any]:
    """Subscribe to a run: every progress value from index ``from`` (0: the first), each status
    change, then the outcome, once, after which the subscription ends."""
    client._check_sub(msg)
    e = runs_of(client.fleet).get(msg.get("run_id"))
    first = msg.get("from", 0)
    if not isinstance(first, int) or isinstance(first, bool) or first < 0:
        raise Usage(f"from is a progress index (0 or more), not {first!r}")
    client._subscribe(msg, _push(client, msg.get("sub"), e, first))
    return {"run": run_json(e)}


async def _push(client: Any, sub: Any, e: RunEntry, index: int) -> None:
    if e.job is not None:
        rec = e.job._rec
        status = "running"
        while True:
            items, nxt = rec.progress_from(index)
            for i, v in enumerate(items, nxt - len(items)):
                client.send({"sub": sub, "progress": progress_json(rec.channel, i, v)})
            index = nxt
            if rec.done and rec.received <= index:
                break
            if rec.status != status and not rec.done:
                status = rec.status
                client.send({"sub": sub, "status": status})
            if rec.received <= index and not rec.done:
                await wait_change(rec)
    client.send({"sub": sub, "result": outcome_json(e)})  # the last: the subscription ends with it


async def wait_change(rec: Any) -> None:
    """Until the run ``rec`` changes (a progress value, a status, the end)."""
    fut: "asyncio.Future[None]" = asyncio.get_running_loop().create_future()

    def wake() -> None:
        if not fut.done():
            fut.set_result(None)
    rec.wakers.append(wake)
    try:
        await fut
    finally:
        rec.wakers.remove(wake)


def timeout_of(msg: Dict[str, Any]) -> Optional[float]:
    t = msg.get("timeout")
    return float(t) if isinstance(t, (int, float)) else None
