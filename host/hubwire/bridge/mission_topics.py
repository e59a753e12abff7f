"""Missions on MQTT (docs/MQTT.md "Missions"): a goal in on ``<prefix>/<board>/mission/<mission>/start``,
a cancel in on ``.../cancel``; out, every run's ``progress`` (QoS 0), its ``result`` (QoS 1, once per
run id, kept across a broker outage like an event) and the mission's retained ``state``; every
message names its run by ``run_id``.

Runs live in the service's one table (:mod:`.mission_runs`), so the topics follow every run of the
bridge's boards, whether it was started here, by a socket client or on the dashboard, and a start
repeated with the same run id (a QoS 1 redelivery, a flow that retries) starts nothing.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Dict, Optional, Tuple

from ..errors import HubwireError, NakError
from ..daemon.mission_ops import outcome_json, wait_change
from ..daemon.mission_runs import RunEntry, Usage, check_run_id, runs_of  # Usage: the service's refusal
from .topics import BadPayload, Topics, codec_json, dumps, level, parse_value, to_json

if TYPE_CHECKING:
    from .board import BoardBridge
    from .mqtt import Bridge
    from .reply import Reply

__all__ = ["filters", "parse", "command", "watch", "MAX_PAYLOAD", "OPS"]

#: what a client publishes to a mission (the op is the last topic level)
OPS = ("start", "cancel")
#: the largest start or cancel payload taken (a goal is at most 254 bytes on the wire; as JSON a
#: few KiB at most); a larger one is refused unparsed
MAX_PAYLOAD = 8192


def filters(t: Topics) -> Tuple[str, ...]:
    return tuple(f"{t.prefix}/+/mission/+/{op}" for op in OPS)


def topic(t: Topics, key: str, mission: str, what: str) -> str:
    return t.board(key, "mission", level(mission), what)


def parse(t: Topics, name: str) -> Optional[Tuple[str, str, str]]:
    """``(board, "mission:" + op, mission level)`` of a mission command topic, else None."""
    head = t.prefix + "/"
    parts = name[len(head):].split("/") if name.startswith(head) else []
    if len(parts) == 4 and parts[1] == "mission" and parts[3] in OPS:
        return parts[0], "mission:" + parts[3], parts[2]
    return None


def _run_id(rid: Any) -> str:
    try:
        return check_run_id(rid)
    except Usage as u:
        raise BadPayload(str(u)) from None


def _envelope(payload: bytes) -> Tuple[Any, Optional[str], bool]:
    """``(goal, run_id, has_goal)`` of a start: ``{"run_id": ..., "goal": ...}`` (either may be left
    out), or any other JSON as the goal itself, or empty for a mission without goal."""
    if len(payload) > MAX_PAYLOAD:
        raise BadPayload(f"a mission payload is at most {MAX_PAYLOAD} bytes, not {len(payload)}")
    body = parse_value(payload, empty_is_none=True)
    if isinstance(body, dict) and body and set(body) <= {"run_id", "goal"}:
        rid = body.get("run_id")
        return body.get("goal"), None if rid is None else _run_id(rid), "goal" in body
    return body, None, body is not None


async def command(bridge: "Bridge", bb: "BoardBridge", op: str, chan: str, payload: bytes, reply: "Reply") -> None:
    """A start or cancel from MQTT, answered on the reply topic (or ``error``) like any command."""
    op = op.split(":", 1)[1]
    ch = bb.t.channel(bb.desc, chan) if bb.desc is not None else None
    name = ch.name if ch is not None else chan
    try:
        if not bb.ready or bb.device is None or ch is None:
            if not bb.ready or bb.device is None:
                await reply.error(op, name, "LinkLost", f"board {bb.key} is not ready: nothing was sent")
            else:
                await reply.error(op, name, "UnknownChannel", f"{bb.key} has no mission {chan!r}")
            return
        if not ch.mission:
            await reply.error(op, name, "NotMission", f"channel {ch.name!r} of {bb.key} is not a mission")
            return
        runs = runs_of(bridge.fleet)
        if op == "cancel":
            await _cancel(bridge, bb, ch, payload, reply)
            return
        goal, run_id, has_goal = _envelope(payload)
        if has_goal and goal is not None and ch.codec.kind != "void":
            goal = ch.codec.from_json(goal)
        try:
            e = await runs.start(bridge.fleet, bb.key, ch.name, goal, run_id)
        except Usage as u:
            raise BadPayload(str(u)) from None
        except HubwireError as err:  # refused: the result topic says so as well, for that run id
            extra = {"nak": err.error} if isinstance(err, NakError) else {}
            kind = type(err).__name__ if not isinstance(err, NakError) else "Nak"
            await reply.error(op, name, kind, str(err), **extra)
            return
        await reply.ok(run_id=e.run_id, run=e.job.run)
    except BadPayload as err:
        await reply.error(op, name, "InvalidValue", str(err))
    except (ValueError, TypeError, RecursionError) as err:
        await reply.error(op, name, "InvalidValue", f"{type(err).__name__}: {err}")


async def _cancel(bridge: "Bridge", bb: "BoardBridge", ch: Any, payload: bytes, reply: "Reply") -> None:
    """``{"run_id": ...}``, the run id as a JSON string, or empty: the mission's run that is going."""
    if len(payload) > MAX_PAYLOAD:
        raise BadPayload(f"a mission payload is at most {MAX_PAYLOAD} bytes, not {len(payload)}")
    body = parse_value(payload, empty_is_none=True)
    rid = body.get("run_id") if isinstance(body, dict) else body
    runs = runs_of(bridge.fleet)
    if rid is None:
        going = [e for e in runs.of_board(bb.key) if e.mission == ch.name and not e.done]
        if not going:
            await reply.ok(cancelled=False, run_id=None)
            return
        e = going[-1]
    else:
        try:
            e = runs.get(_run_id(rid))
        except HubwireError as err:
            await reply.error("cancel", ch.name, getattr(err, "kind", "Error"), str(err))
            return
        if (e.key, e.mission) != (bb.key, ch.name):
            raise BadPayload(f"run {e.run_id!r} is mission {e.mission!r} of board {e.key}")
    done = e.job is None or e.done
    cancelled = False if done else await e.job.cancel()
    await reply.ok(cancelled=cancelled, run_id=e.run_id)


# ------------------------------------------------------------------------------ publishing

def watch(bridge: "Bridge") -> Callable[[], None]:
    """Follow every run of the fleet's table from now on (its progress, state and result); returns
    the function that stops it."""
    listeners = runs_of(bridge.fleet).listeners

    def new(e: RunEntry) -> None:
        bridge.spawn(_follow(bridge, e))
    listeners.append(new)
    return lambda: listeners.remove(new) if new in listeners else None


def _state(e: RunEntry, last: Any) -> Dict[str, Any]:
    job = e.job
    return {"run_id": e.run_id, "run": job.run if job is not None else None, "status": e.status,
            "progress": last, "received": job._rec.received if job is not None else 0}


async def _follow(bridge: "Bridge", e: RunEntry) -> None:
    t = bridge.topics
    state = topic(t, e.key, e.mission, "state")
    last: Any = None
    if e.job is not None:
        rec = e.job._rec
        ch = rec.channel
        index = 0
        status = None
        while True:
            items, nxt = rec.progress_from(index)
            for i, v in enumerate(items, nxt - len(items)):
                last = codec_json(ch.progress, v) if ch.progress is not None else None
                await bridge.send(topic(t, e.key, e.mission, "progress"),
                                  dumps({"run_id": e.run_id, "run": rec.run, "index": i, "value": last}))
            if items:
                bridge.outbox.put_latest(state, dumps(_state(e, last)))
            index = nxt
            if rec.done and rec.received <= index:
                break
            if rec.status != status:
                status = rec.status
                bridge.outbox.put_latest(state, dumps(_state(e, last)))
            if rec.received <= index and not rec.done:
                await wait_change(rec)
    o = outcome_json(e)
    o.pop("raw", None)
    if "value" in o:  # an f32 as its shortest decimal, as every state
        o["value"] = to_json(e.job._rec.channel, e.job._rec.result, returns=True) if e.job is not None \
            else to_json(None, o["value"])
    body = {"run_id": e.run_id, "run": e.job.run if e.job is not None else None, **o}
    bridge.outbox.put_event(topic(t, e.key, e.mission, "result"), dumps(body))
    if e.job is None and any(o.mission == e.mission and not o.done for o in runs_of(bridge.fleet).of_board(e.key)):
        return  # a start refused while a run goes (BUSY): the state stays that run's
    bridge.outbox.put_latest(state, dumps({**_state(e, last), **{k: v for k, v in body.items() if k != "run"}}))

