"""One board on the broker: its descriptor, link state, channel states, streams, events and commands.

A ``BoardBridge`` lives as long as the bridge knows the board's key; the board's device may change
under it (unplug and replug: a new ``AsyncDevice``), and it follows.
"""
from __future__ import annotations

import asyncio
import json
import math
import time
from typing import TYPE_CHECKING, Any, Dict, List, Optional, Tuple

from ..descriptor import Channel, Descriptor
from ..diagnose import access_error
from ..errors import HubwireError, InvalidValue, NakError, error_type
from ..session import ReceivedEvent, StreamSample
from . import ha
from .topics import OFFLINE, ONLINE, BadPayload, dumps, parse_value, to_json

if TYPE_CHECKING:
    from ..aio import AsyncDevice
    from .mqtt import Bridge
    from .reply import Reply

__all__ = ["BoardBridge"]

_NEEDS = {"set": "w", "call": "c", "read": "r"}


class BadRequest(Exception):
    """A command the bridge refuses whole (answered ``BadRequest``): a reply topic outside the
    reply prefixes."""


class BoardBridge:
    def __init__(self, bridge: "Bridge", key: str) -> None:
        self.bridge = bridge
        self.key = key
        self.t = bridge.topics
        self.board: Any = None
        self.device: Optional["AsyncDevice"] = None
        self.desc: Optional[Descriptor] = None
        self._tasks: List["asyncio.Task[Any]"] = []
        self._remove_cbs: List[Any] = []
        #: events published by this run of the bridge for this board (the ``n`` of event ids)
        self.events = 0
        #: per channel: who asked for its stream ({client: (hz, expires)}) and the running task
        self.leases: Dict[str, Dict[str, Tuple[float, float]]] = {}
        self.stream_tasks: Dict[str, Tuple[float, "asyncio.Task[Any]"]] = {}
        self._discovery: List[str] = []

    # -------------------------------------------------------------------------- board state

    @property
    def ready(self) -> bool:
        return self.board is not None and self.board.state == "ready" and self.device is not None

    def update(self, board: Any) -> None:
        """The fleet changed this board (state, port or device)."""
        self.board = board
        if board.device is not self.device:
            self._detach()
            if board.device is not None:
                self._attach(board.device)
        desc = self._descriptor()
        if self.ready and desc is not None and desc is not self.desc:
            self.desc = desc
            self._restart_tasks()
            self.publish_discovery()
        self.publish_descriptor()
        self.bridge.outbox.put_latest(self.t.status(self.key), ONLINE if self.ready else OFFLINE)

    def _descriptor(self) -> Optional[Descriptor]:
        dev = self.device
        return dev.core.descriptor if dev is not None else None

    def _attach(self, dev: "AsyncDevice") -> None:
        self.device = dev
        self._remove_cbs.append(dev.on("*", self._on_event))
        self._remove_cbs.append(dev.on("reconnect", self._on_reconnect))

    def _detach(self) -> None:
        for rm in self._remove_cbs:
            rm()
        self._remove_cbs.clear()
        self._stop_tasks()
        self.device = None
        self.desc = None

    def close(self) -> None:
        self._detach()

    def _on_reconnect(self, desc: Descriptor) -> None:
        """The device rebooted (perhaps with new firmware): its channels may have changed."""
        if self.board is not None:
            self.update(self.board)

    # ------------------------------------------------------------------------- descriptor / HA

    def publish_descriptor(self) -> None:
        b = self.board
        desc = self.desc or self._descriptor()
        body: Dict[str, Any] = {"key": self.key, "name": b.name, "board_id": b.board_id, "port": b.port,
                                "state": b.state, "service": self.bridge.config.service_id}
        if desc is not None:
            body["firmware"] = desc.firmware
            body["descriptor"] = json.loads(desc.raw)
        self.bridge.outbox.put_latest(self.t.descriptor(self.key), dumps(body))

    def publish_discovery(self, force: bool = False) -> None:
        cfg = self.bridge.config
        if not cfg.discovery_prefix or self.desc is None:
            return
        msgs = ha.discovery_messages(self.t, cfg.service_id, self.key, self.desc, self.board.board_id)
        box = self.bridge.outbox
        new = [topic for topic, _ in msgs]
        for old in self._discovery:
            if old not in new:
                box.forget(old)  # a channel the new firmware no longer has
        for topic, payload in msgs:
            box.put_latest(topic, payload)
            if force:
                box.dirty[topic] = None
        if force:
            box.wake.set()
        self._discovery = new

    # ------------------------------------------------------------------------------ states

    def _restart_tasks(self) -> None:
        self._stop_tasks()
        dev, desc = self.device, self.desc
        if dev is None or desc is None:
            return
        readable = [ch for ch in desc.channels if ch.readable]
        box, head = self.bridge.outbox, self.t.board(self.key, "state", "")
        for topic in [t for t in box.latest if t.startswith(head)]:
            if self.t.channel(desc, topic[len(head):]) is None:
                box.forget(topic)  # a channel the board's new firmware no longer has
        if readable:
            self._tasks.append(self.bridge.spawn(self._poll_states(dev, readable)))
        for name, hz in self.bridge.config.streams.items():
            board, _, chan = name.rpartition("/")
            if board in ("", self.key) and desc.by_name(chan) is not None:
                self.leases.setdefault(chan, {})["config"] = (hz, math.inf)
        for chan in list(self.leases):
            self._retune(chan)

    def _stop_tasks(self) -> None:
        for t in self._tasks:
            t.cancel()
        self._tasks.clear()
        for _, task in self.stream_tasks.values():
            task.cancel()
        self.stream_tasks.clear()

    def put_state(self, ch: Channel, value: Any) -> None:
        self.bridge.outbox.put_latest(self.t.state(self.key, ch.name), dumps(to_json(ch, value)))

    async def _poll_states(self, dev: "AsyncDevice", chans: List[Channel]) -> None:
        """Read the states: streamable channels (values that move) ``state_hz`` times a second,
        the others every ``poll_s``. Reads, not streams: a board has few stream slots (4 on an
        Uno by default) and they are kept for the clients that ask for streams."""
        cfg = self.bridge.config
        tick = 1.0 / cfg.state_hz
        every = max(1, round(cfg.poll_s / tick))
        n = 0
        while True:
            for ch in chans:
                if (ch.streamable or n % every == 0) and self.ready and self.device is dev:
                    try:
                        self.put_state(ch, await dev.read(ch.name))
                    except HubwireError:
                        pass  # link lost meanwhile: the next round reads it again
            n += 1
            await asyncio.sleep(tick)

    # ------------------------------------------------------------------------------- events

    def _on_event(self, ev: ReceivedEvent) -> None:
        dev, desc = self.device, self._descriptor()
        ch = desc.by_name(ev.name) if desc is not None else None
        hello = dev.core.device_hello if dev is not None else None
        self.events += 1
        body = {"event_type": ev.name, "value": to_json(ch, ev.value),
                "id": f"{self.key}:{self.bridge.run_id}:{self.events}",
                "board": self.key, "nonce": f"{hello.nonce:08x}" if hello is not None else None,
                "seq": ev.seq, "time": time.time() - (time.monotonic() - ev.time)}
        self.bridge.outbox.put_event(self.t.event(self.key, ev.name), dumps(body))

    # ------------------------------------------------------------------------------ streams

    def _rate(self, chan: str) -> float:
        now = time.monotonic()
        held = self.leases.get(chan, {})
        for who in [w for w, (_, exp) in held.items() if exp <= now]:
            del held[who]
        want = max((hz for hz, _ in held.values()), default=0.0)
        return min(want, self.bridge.config.ceiling(self.key, chan))

    def _retune(self, chan: str) -> None:
        """Run the published stream of ``chan`` at the highest rate asked for (0: stop it)."""
        hz = self._rate(chan)
        cur = self.stream_tasks.get(chan)
        if cur is not None and cur[0] == hz:
            return
        if cur is not None:
            cur[1].cancel()
            del self.stream_tasks[chan]
        if hz > 0 and self.device is not None and self.desc is not None:
            ch = self.desc.by_name(chan)
            if ch is not None:
                self.stream_tasks[chan] = (hz, self.bridge.spawn(self._publish_stream(self.device, ch, hz)))

    async def _publish_stream(self, dev: "AsyncDevice", ch: Channel, hz: float) -> None:
        topic = self.t.stream(self.key, ch.name)
        # a token bucket holds the rate at ``hz`` when a faster consumer of the same device (the
        # dashboard, a script) makes the board send more often; it runs on the board's clock (the
        # ms between samples each sample carries), so samples that bunch up on a busy hub all pass
        credit = 2.0
        wall = time.time() - time.monotonic()
        async with dev.stream(ch.name, hz=hz, meta=True) as s:
            async for sample in s:
                assert isinstance(sample, StreamSample)
                credit = min(3.0, credit + sample.since_ms / 1000.0 * hz * 1.02)
                if credit < 1.0:
                    continue
                credit -= 1.0
                body = {"v": to_json(ch, sample.value), "seq": sample.seq, "t": wall + sample.time}
                if sample.lost:
                    body["lost"] = sample.lost
                if sample.gap:
                    body["gap"] = sample.gap
                await self.bridge.send(topic, dumps(body))
            if self.stream_tasks.get(ch.name, (0, None))[1] is asyncio.current_task():
                del self.stream_tasks[ch.name]

    async def _expire(self, chan: str, after: float) -> None:
        await asyncio.sleep(after)
        self._retune(chan)

    # ----------------------------------------------------------------------------- commands

    async def command(self, op: str, chan: Optional[str], payload: bytes, reply: "Reply") -> None:
        """Carry out one command and answer it; every malformed one gets a typed error."""
        try:
            if op == "rpc":
                op, chan, payload = self._unwrap(payload, reply)
            elif chan is not None and self.desc is not None:
                ch = self.t.channel(self.desc, chan)  # a topic level: the channel it stands for
                chan = ch.name if ch is not None else chan
            await self._command(op, chan or "", payload, reply)
        except BadRequest as e:
            await reply.error(op, chan, "BadRequest", str(e))
        except BadPayload as e:
            await reply.error(op, chan, "InvalidValue", str(e))
        except RecursionError:
            await reply.error(op, chan, "BadRequest", "payload nested too deeply")
        except (ValueError, TypeError, UnicodeError) as e:
            await reply.error(op, chan, "InvalidValue", f"{type(e).__name__}: {e}")
        except Exception as e:  # noqa: BLE001  (a reply, whatever went wrong: no client waits forever)
            await reply.error(op, chan, "Error", f"{type(e).__name__}: {e}")

    def _unwrap(self, payload: bytes, reply: "Reply") -> Tuple[str, str, bytes]:
        """An ``rpc`` envelope: ``{"op", "channel", "value", "id", "reply_to"}``."""
        env = parse_value(payload)
        if not isinstance(env, dict):
            raise BadPayload('rpc payload must be a JSON object {"op": ..., "channel": ..., "value": ..., "id": ...}')
        reply.envelope(env.get("reply_to"), env.get("id"))
        if reply.refused is not None:
            raise BadRequest(reply.refused)
        op, chan = env.get("op"), env.get("channel")
        if op not in ("set", "call", "read", "subscribe", "unsubscribe") or not isinstance(chan, str):
            raise BadPayload("rpc needs \"op\" (set, call, read, subscribe, unsubscribe) and \"channel\"")
        return op, chan, dumps(env["value"]).encode() if "value" in env else b""

    async def _command(self, op: str, chan: str, payload: bytes, reply: "Reply") -> None:
        desc = self.desc
        dev = self.device
        if not self.ready or dev is None or desc is None:
            state = self.board.state if self.board is not None else "unknown"
            await reply.error(op, chan, "LinkLost", f"board {self.key} is {state}: nothing was sent")
            return
        ch = desc.by_name(chan)
        if ch is None:
            await reply.error(op, chan, "UnknownChannel", f"{self.key} has no channel {chan!r}; channels: "
                              + ", ".join(c.name for c in desc.channels))
            return
        if op in ("subscribe", "unsubscribe"):
            if not ch.streamable:
                await reply.error(op, chan, "NotStreamable", f"channel {chan!r} cannot be streamed "
                                  f"(access {ch.access!r}); read it, or follow its state topic")
                return
            await self._subscribe(op, ch, payload, reply)
            return
        bad = access_error(chan, ch.access, _NEEDS[op])
        if bad is not None:
            await reply.error(op, chan, bad[0], bad[1])
            return
        try:
            if op == "read":
                value = await dev.read(chan)
                self.put_state(ch, value)
                await reply.ok(value=to_json(ch, value))
                return
            if op == "set":
                value = ch.codec.from_json(parse_value(payload))
                await dev.write(chan, value)
                await reply.ok()
            else:
                arg = parse_value(payload, empty_is_none=True)
                arg = None if arg is None else ch.codec.from_json(arg)
                result = await dev.call(chan, arg)
                # the last call, retained: Home Assistant's entities of the action show it
                self.bridge.outbox.put_latest(self.t.result(self.key, ch.name), dumps(
                    {"arg": to_json(ch, arg), "value": to_json(ch, result, returns=True)}))
                await reply.ok(value=to_json(ch, result, returns=True))
        except BadPayload:
            raise
        except (HubwireError, ValueError, TypeError) as e:
            extra = {"nak": e.error} if isinstance(e, NakError) else {}
            if isinstance(e, InvalidValue):
                extra = {"code": e.error}
            kind = error_type(e) if isinstance(e, HubwireError) and error_type(e) != "Error" else "InvalidValue"
            await reply.error(op, chan, kind, str(e), **extra)
            return
        if op == "set" and not ch.readable:
            self.put_state(ch, value)  # a write-only channel's state: the value the board accepted
        elif op == "set":
            try:
                self.put_state(ch, await dev.read(chan))  # the state topic confirms the write
            except HubwireError:
                pass

    async def _subscribe(self, op: str, ch: Channel, payload: bytes, reply: "Reply") -> None:
        body = parse_value(payload, empty_is_none=True)
        if body is None:
            body = {}
        if isinstance(body, (int, float)) and not isinstance(body, bool):
            body = {"hz": body}
        if not isinstance(body, dict):
            raise BadPayload('subscribe takes {"hz": 10, "client": "me", "lease_s": 60} (all optional) or a number')
        who = str(body.get("client") or reply.topic or "anonymous")
        held = self.leases.setdefault(ch.name, {})
        if op == "unsubscribe":
            held.pop(who, None)
            self._retune(ch.name)
            await reply.ok(hz=self._rate(ch.name))
            return
        hz, lease = body.get("hz", 10), body.get("lease_s", self.bridge.config.lease_s)
        if (not isinstance(hz, (int, float)) or isinstance(hz, bool) or not 0 < hz <= 1000
                or not isinstance(lease, (int, float)) or isinstance(lease, bool) or not 0 < lease <= 86400):
            raise BadPayload("hz must be a number in (0, 1000] and lease_s in (0, 86400]")
        held[who] = (float(hz), time.monotonic() + float(lease))
        self._retune(ch.name)
        self.bridge.spawn(self._expire(ch.name, float(lease) + 0.01))
        ceiling = self.bridge.config.ceiling(self.key, ch.name)
        await reply.ok(topic=self.t.stream(self.key, ch.name), hz=min(float(hz), ceiling),
                       published_hz=self._rate(ch.name), max_rate_hz=ceiling, lease_s=float(lease))
