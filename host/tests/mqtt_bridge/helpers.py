"""A stand-in for the service's fleet (the shape of hubwire.daemon.fleet, built from
hubwire.aio.connect() on emulated boards), an MQTT test client, and a running bridge."""
from __future__ import annotations

import asyncio
import contextlib
import json
import struct
import uuid
from dataclasses import dataclass
from typing import Any, AsyncIterator, Dict, List, Optional, Tuple

import aiomqtt
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

import hubwire.aio
from hubwire.bridge.mqtt import NODELAY, Bridge
from hubwire.bridge.topics import BridgeConfig


@dataclass
class Board:
    key: str
    name: str
    board_id: Optional[str]
    port: Optional[str]
    state: str
    device: Optional[hubwire.aio.AsyncDevice]


class StandInFleet:
    """Boards connected with hubwire.aio.connect(); link state from the device's callbacks."""

    def __init__(self, cache_dir: str) -> None:
        self.cache_dir = cache_dir
        self._boards: Dict[str, Board] = {}
        self._queues: List["asyncio.Queue[Board]"] = []

    def boards(self) -> List[Board]:
        return list(self._boards.values())

    def get(self, key: str) -> Board:
        try:
            return self._boards[key]
        except KeyError:
            raise KeyError(f"no board {key!r}; boards: {', '.join(self._boards)}") from None

    async def changes(self) -> AsyncIterator[Board]:
        q: "asyncio.Queue[Board]" = asyncio.Queue()
        self._queues.append(q)
        try:
            while True:
                yield await q.get()
        finally:
            self._queues.remove(q)

    def _changed(self, b: Board) -> None:
        for q in self._queues:
            q.put_nowait(b)

    def _set(self, b: Board, state: str) -> None:
        b.state = state
        self._changed(b)

    async def plug(self, key: str, link: str) -> Board:
        """A board appears on ``link`` (first time, or replugged on a new path)."""
        dev = await hubwire.aio.connect(link, cache_dir=self.cache_dir)
        b = self._boards.get(key)
        if b is None:
            b = self._boards[key] = Board(key, dev.name, None, link, "ready", dev)
        else:
            b.port, b.device, b.state = link, dev, "ready"
        dev.on("link_lost", lambda: self._set(b, "lost"))
        dev.on("link_restored", lambda: self._set(b, "ready" if dev.state == "ready" else "connecting"))
        dev.on("reconnect", lambda _d: self._set(b, "ready"))
        self._changed(b)
        return b

    async def unplug(self, key: str) -> None:
        b = self._boards[key]
        dev, b.device, b.port, b.state = b.device, None, None, "unplugged"
        self._changed(b)
        if dev is not None:
            await dev.close()

    async def close(self) -> None:
        for b in self._boards.values():
            if b.device is not None:
                await b.device.close()


@contextlib.asynccontextmanager
async def running_bridge(fleet: StandInFleet, port: int, **settings: Any) -> AsyncIterator[Bridge]:
    settings.setdefault("service_id", "test")
    settings.setdefault("reconnect_s", 0.2)
    bridge = Bridge(fleet, "127.0.0.1", port, BridgeConfig(**settings))
    task = asyncio.get_running_loop().create_task(bridge.run())
    try:
        await asyncio.wait_for(bridge.connected.wait(), 10)
        yield bridge
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


class Watcher:
    """An MQTT client that records what it receives: ``last[topic]``, ``all`` in order."""

    def __init__(self, client: aiomqtt.Client) -> None:
        self.client = client
        self.all: List[Tuple[str, bytes, bool]] = []
        self.last: Dict[str, bytes] = {}
        self.retained: Dict[str, bool] = {}
        self.changed = asyncio.Event()
        self.replies: Dict[bytes, "asyncio.Future[Any]"] = {}
        self.reply_topic = f"hubwire/replies/{uuid.uuid4().hex}"  # under the bridge's reply prefix
        self._task = asyncio.get_running_loop().create_task(self._read())

    async def _read(self) -> None:
        async for msg in self.client.messages:
            topic = str(msg.topic)
            payload = msg.payload if isinstance(msg.payload, bytes) else str(msg.payload).encode()
            corr = getattr(msg.properties, "CorrelationData", None) if msg.properties is not None else None
            if corr is not None and corr in self.replies and topic == self.reply_topic:
                fut = self.replies.pop(corr)
                if not fut.done():
                    fut.set_result(json.loads(payload))
            self.all.append((topic, payload, bool(msg.retain)))
            self.last[topic] = payload
            self.retained.setdefault(topic, bool(msg.retain))  # of the first: came from the store
            self.changed.set()

    def json(self, topic: str) -> Any:
        return json.loads(self.last[topic])

    def on(self, topic: str) -> List[Any]:
        return [json.loads(p) for t, p, _ in self.all if t == topic]

    async def wait_quiet(self, topic: str, quiet: float, timeout: float = 20.0) -> int:
        """Wait until nothing new arrives on ``topic`` for ``quiet`` s (what was already on its way has
        come, however busy the machine); returns the count then."""
        deadline = asyncio.get_running_loop().time() + timeout
        n = len(self.on(topic))
        while True:
            await asyncio.sleep(quiet)
            now = len(self.on(topic))
            if now == n:
                return n
            if asyncio.get_running_loop().time() > deadline:
                raise AssertionError(f"{topic} still receiving after {timeout} s ({now} messages)")
            n = now

    async def wait_for(self, pred: Any, timeout: float = 10.0, what: str = "a message") -> None:
        async def loop() -> None:
            while not pred():
                self.changed.clear()
                await self.changed.wait()
        try:
            await asyncio.wait_for(loop(), timeout)
        except asyncio.TimeoutError:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}") from None

    async def request(self, topic: str, payload: Any, timeout: float = 10.0) -> Any:
        """A command with an MQTT 5 response topic and correlation data; its reply."""
        corr = uuid.uuid4().bytes
        fut: "asyncio.Future[Any]" = asyncio.get_running_loop().create_future()
        self.replies[corr] = fut
        props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
        props.ResponseTopic = self.reply_topic
        props.CorrelationData = corr
        await self.client.publish(topic, payload, qos=1, properties=props)
        return await asyncio.wait_for(fut, timeout)

    def close(self) -> None:
        self._task.cancel()


@contextlib.asynccontextmanager
async def watcher(port: int, *topics: str, identifier: Optional[str] = None, persistent: bool = False,
                  v311: bool = False) -> AsyncIterator[Watcher]:
    """A client subscribed (QoS 1) to ``topics`` and its reply topic; ``persistent``: a session the
    broker keeps for an hour (clean_start False), so QoS 1 messages wait for it while it is away."""
    kw: Dict[str, Any] = {}
    if v311:
        kw.update(protocol=aiomqtt.ProtocolVersion.V311, clean_session=not persistent)
    else:
        props = Properties(PacketTypes.CONNECT)  # type: ignore[no-untyped-call]
        if persistent:
            props.SessionExpiryInterval = 3600
        kw.update(protocol=aiomqtt.ProtocolVersion.V5, clean_start=not persistent, properties=props)
    async with aiomqtt.Client("127.0.0.1", port, identifier=identifier, socket_options=NODELAY, **kw) as client:
        w = Watcher(client)
        if not v311:
            await client.subscribe(w.reply_topic, qos=1)
        for t in topics:
            await client.subscribe(t, qos=1)
        try:
            yield w
        finally:
            w.close()


def f32_shortest(x: float) -> float:
    """The shortest decimal that is the same f32 as ``x`` (what the bridge publishes for an f32)."""
    same = struct.pack("<f", x)
    return next(float(f"{x:.{d}g}") for d in range(1, 10) if struct.pack("<f", float(f"{x:.{d}g}")) == same)
