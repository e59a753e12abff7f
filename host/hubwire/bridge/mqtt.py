"""The MQTT bridge: every board of a fleet on a broker (docs/MQTT.md has the topic layout).

``hubwire serve --mqtt HOST:PORT`` runs :func:`run_bridge` on the service's loop next to its fleet.
The bridge keeps its own connection to the broker up (reconnecting with the same last will), and
works from the fleet's shape only: ``boards()``, ``get(key)`` and ``changes()`` of boards with
``key``, ``name``, ``board_id``, ``port``, ``state`` and ``device`` (an ``AsyncDevice``).
"""
from __future__ import annotations

import asyncio
import json
import logging
import secrets
import socket
import ssl
from typing import TYPE_CHECKING, Any, AsyncIterator, Dict, List, Optional, Protocol, Sequence, Set, Tuple

import aiomqtt
from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from . import mission_topics
from .board import BoardBridge
from .inbound import Inbound
from .reply import Reply
from .outbox import Outbox
from .retire import Retired
from .topics import OFFLINE, ONLINE, BridgeConfig, Topics

if TYPE_CHECKING:
    from ..aio import AsyncDevice

__all__ = ["run_bridge", "Bridge", "BridgeConfig", "FleetLike", "BoardLike"]

log = logging.getLogger("hubwire.mqtt")

#: aiomqtt's own log: it warns whenever more than 10 publishes wait for the socket, which is
#: normal for streams at full rate (they wait their turn), so only its errors are shown
_client_log = logging.getLogger("hubwire.mqtt.client")
if _client_log.level == logging.NOTSET:
    _client_log.setLevel(logging.ERROR)

#: small messages go out at once (with Nagle's algorithm a reply waits for the peer's delayed ACK)
NODELAY = ((socket.IPPROTO_TCP, socket.TCP_NODELAY, 1),)

#: commands waiting for a worker; beyond it they are dropped (and counted)
INBOUND_QUEUE = 256
#: commands taken per second, on average, and in one burst; beyond it they are dropped (and counted)
INBOUND_RATE_HZ = 200.0
INBOUND_BURST = 200
#: a command costs one token more for each of these bytes of payload (parsing it takes longer)
INBOUND_BYTES_PER_TOKEN = 16 * 1024
#: payload bytes of the commands waiting for a worker; beyond it they are dropped (and counted)
INBOUND_BYTES = 4 << 20
#: commands carried out at once (each waits for its board)
WORKERS = 8
#: a warning about dropped commands at most this often, seconds
DROP_LOG_INTERVAL_S = 10.0
#: messages aiomqtt holds before the bridge takes them (the bridge takes them at once), and their
#: payload bytes; beyond either it drops them
CLIENT_QUEUE = 4 * INBOUND_QUEUE
CLIENT_BYTES = 8 << 20
#: boards of other services remembered (from their retained descriptors)
MAX_ELSEWHERE = 4096
#: the largest MQTT packet the bridge takes, bytes (as a socket client's line, docs/SERVICE.md
#: "Limits"): the broker is told so at connect and drops larger ones for us (MQTT 5 Maximum Packet
#: Size), and one that comes anyway is dropped unread. Parsing a value of many megabytes holds the
#: loop long enough for the boards to miss their heartbeats; the largest command (a 65,535-byte
#: value as JSON) is far below it.
MAX_PACKET = 1 << 20


def _size(msg: aiomqtt.Message) -> int:
    return len(msg.payload) if isinstance(msg.payload, (bytes, bytearray)) else 0


class ClientQueue(asyncio.Queue[aiomqtt.Message]):
    """aiomqtt's queue of messages for the bridge, full at CLIENT_QUEUE messages or CLIENT_BYTES of
    payload (aiomqtt drops a message that finds it full)."""

    def __init__(self, maxsize: int = 0) -> None:
        super().__init__(maxsize)
        self.bytes = 0

    def full(self) -> bool:
        return super().full() or self.bytes >= CLIENT_BYTES

    def _put(self, item: aiomqtt.Message) -> None:
        self.bytes += _size(item)
        super()._put(item)

    def _get(self) -> aiomqtt.Message:
        item: aiomqtt.Message = super()._get()
        self.bytes -= _size(item)
        return item


class BoardLike(Protocol):
    """A board as the service's fleet has it (docs of ``hubwire.daemon.fleet.Board``)."""

    key: str
    name: str
    board_id: Optional[str]
    port: Optional[str]
    state: str
    device: Optional["AsyncDevice"]


class FleetLike(Protocol):
    def boards(self) -> List[Any]: ...

    def get(self, key: str) -> Any: ...

    def changes(self) -> AsyncIterator[Any]: ...


async def run_bridge(fleet: FleetLike, host: str, port: int = 1883, *, prefix: str = "hubwire",
                     config: Optional[BridgeConfig] = None, username: Optional[str] = None,
                     password: Optional[str] = None, tls_context: Optional[ssl.SSLContext] = None,
                     reply_prefixes: Sequence[str] = (), **settings: Any) -> None:
    """Bridge ``fleet`` to the MQTT broker at ``host:port`` until cancelled.

    ``settings`` are fields of :class:`BridgeConfig` (``discovery_prefix``, ``service_id``,
    ``max_rate_hz``, ``streams``, ...), or pass a whole ``config``. ``tls_context``: connect over
    TLS (``hubwire.bridge.broker.BrokerSettings.tls_context``); ``reply_prefixes``: where replies
    may be published (default: under ``prefix``).
    """
    cfg = config or BridgeConfig(prefix=prefix, **settings)
    await Bridge(fleet, host, port, cfg, username=username, password=password, tls_context=tls_context,
                 reply_prefixes=reply_prefixes).run()


class Bridge:
    """One fleet on one broker. :meth:`run` until cancelled; ``connected`` is set while the broker
    has us (tests and the bench wait on it)."""

    def __init__(self, fleet: FleetLike, host: str, port: int, config: BridgeConfig, *,
                 username: Optional[str] = None, password: Optional[str] = None,
                 tls_context: Optional[ssl.SSLContext] = None, reply_prefixes: Sequence[str] = ()) -> None:
        self.fleet = fleet
        self.host = host
        self.port = port
        self.config = config
        self.username = username
        self.password = password
        self.tls_context = tls_context
        self.topics = Topics(config.prefix, config.discovery_prefix)
        #: replies go only under these (a sender must not make the bridge publish anywhere it likes)
        self.reply_prefixes: Tuple[str, ...] = tuple(
            p if p.endswith("/") else p + "/" for p in (reply_prefixes or (self.topics.prefix,)))
        self.inbound: "Inbound[Tuple[aiomqtt.Message, str, str, Optional[str]]]" = Inbound(
            INBOUND_QUEUE, INBOUND_RATE_HZ, INBOUND_BURST, DROP_LOG_INTERVAL_S, log,
            bytes_per_token=INBOUND_BYTES_PER_TOKEN, max_bytes=INBOUND_BYTES)
        self.outbox = Outbox(config.event_backlog)
        #: names this run of the bridge in event ids, so ids never repeat across restarts
        self.run_id = secrets.token_hex(4)
        self.boards: Dict[str, BoardBridge] = {}
        self.client: Optional[aiomqtt.Client] = None
        self.connected = asyncio.Event()
        self.connections = 0
        #: boards other services on the same broker announce (key: service id), from their descriptors
        self.elsewhere: Dict[str, str] = {}
        #: keys this service published that a board no longer has (their retained topics are cleared)
        self.retired = Retired(self.topics, config.service_id)
        self._tasks: Set["asyncio.Task[Any]"] = set()
        self._failing = False
        #: messages over MAX_PACKET that came although the broker was told (dropped unread)
        self.oversized = 0
        #: commands refused for their reply topic; when that was last logged
        self.refusals = 0
        self._refusal_logged_at: Optional[float] = None

    # ---------------------------------------------------------------------------- lifecycle

    async def run(self) -> None:
        loop = asyncio.get_running_loop()
        watcher = loop.create_task(self._watch_fleet())
        unwatch_missions = mission_topics.watch(self)
        workers = [loop.create_task(self._worker()) for _ in range(WORKERS)]
        try:
            while True:
                try:
                    await self._session()
                except aiomqtt.MqttError as e:
                    # the first failure of a streak shows without -v (a refused password, a bad certificate)
                    (log.info if self._failing else log.warning)("hubwire serve: MQTT: broker %s:%d: %s",
                                                                 self.host, self.port, e)
                    self._failing = True
                self.client = None
                self.connected.clear()
                await asyncio.sleep(self.config.reconnect_s)
        finally:
            watcher.cancel()
            unwatch_missions()
            for w in workers:
                w.cancel()
            for b in self.boards.values():
                b.close()
            for t in list(self._tasks):
                t.cancel()

    async def _session(self) -> None:
        status = self.topics.service_status(self.config.service_id)
        will = aiomqtt.Will(status, OFFLINE, qos=1, retain=True)
        connect = Properties(PacketTypes.CONNECT)  # type: ignore[no-untyped-call]
        connect.MaximumPacketSize = MAX_PACKET
        async with aiomqtt.Client(self.host, self.port, identifier=f"hubwire-{self.config.service_id}",
                                  protocol=aiomqtt.ProtocolVersion.V5, will=will, clean_start=True,
                                  keepalive=self.config.keepalive, username=self.username,
                                  password=self.password, socket_options=NODELAY,
                                  tls_context=self.tls_context, logger=_client_log,
                                  max_queued_incoming_messages=CLIENT_QUEUE, queue_type=ClientQueue,
                                  properties=connect) as client:
            self.client = client
            self.connections += 1
            self._failing = False
            await client.publish(status, ONLINE, qos=1, retain=True)
            for f in self.topics.command_filters() + mission_topics.filters(self.topics):
                await client.subscribe(f, qos=1)
            await client.subscribe(self.topics.descriptor_filter(), qos=1)
            if self.config.discovery_prefix:
                await client.subscribe(f"{self.config.discovery_prefix}/status", qos=1)
            self.outbox.all_dirty()
            loop = asyncio.get_running_loop()
            tasks = (loop.create_task(self._publisher(client)), loop.create_task(self._receive(client)))
            self.connected.set()
            try:
                # either ending ends the session (a publish that timed out, the connection lost)
                done, _ = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
                for t in done:
                    t.result()
            except asyncio.CancelledError:
                # a clean stop: say so (a clean disconnect drops the will); the service awaits this
                try:
                    await asyncio.wait_for(client.publish(status, OFFLINE, qos=1, retain=True), 1.0)
                except (aiomqtt.MqttError, asyncio.TimeoutError):
                    pass
                raise
            finally:
                for t in tasks:
                    t.cancel()

    async def _receive(self, client: aiomqtt.Client) -> None:
        async for msg in client.messages:
            self._on_message(msg)

    async def _publisher(self, client: aiomqtt.Client) -> None:
        """Flush the outbox: last values, then events in order, each event until acknowledged."""
        box = self.outbox
        while True:
            await box.wake.wait()
            box.wake.clear()
            while True:
                item = box.take_latest()
                if item is None:
                    break
                try:
                    await client.publish(item[0], item[1], qos=1, retain=True)
                except aiomqtt.MqttError:
                    box.requeue_latest(*item)
                    raise
            while box.events:
                topic, payload = box.events[0]
                await client.publish(topic, payload, qos=1)  # raises when the connection drops: kept
                if box.events and box.events[0] == (topic, payload):
                    box.events.popleft()
                if box.dirty:
                    box.wake.set()
                    break

    # -------------------------------------------------------------------------------- fleet

    async def _watch_fleet(self) -> None:
        for b in self.fleet.boards():
            self._board_changed(b)
        async for b in self.fleet.changes():
            self._board_changed(b)

    def _board_changed(self, board: Any) -> None:
        bb = self.boards.get(board.key)
        if bb is None:
            bb = self.boards[board.key] = BoardBridge(self, board.key)
            for t in self.retired.seen(board.key, (board.name, board.board_id)):
                self.outbox.forget(t)
        bb.update(board)

    # ------------------------------------------------------------------------------ sending

    def spawn(self, coro: Any) -> "asyncio.Task[Any]":
        task = asyncio.get_running_loop().create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task

    async def send(self, topic: str, payload: str, *, qos: int = 0,
                   properties: Optional[Properties] = None) -> bool:
        """Publish now if connected (streams, replies); False when it could not go out."""
        client = self.client
        if client is None:
            return False
        try:
            await client.publish(topic, payload, qos=qos, properties=properties)
            return True
        except aiomqtt.MqttError:
            return False
        except (ValueError, TypeError) as e:  # a topic paho refuses: checked before, so a bug
            log.error("hubwire serve: MQTT: could not publish to %r: %s", topic, e)
            return False

    # ----------------------------------------------------------------------------- commands

    def _on_message(self, msg: aiomqtt.Message) -> None:
        payload = msg.payload
        if isinstance(payload, (bytes, bytearray)) and len(payload) > MAX_PACKET:
            self.oversized += 1  # a broker that ignored our Maximum Packet Size
            return
        topic = str(msg.topic)
        if self.config.discovery_prefix and topic == f"{self.config.discovery_prefix}/status":
            if bytes(msg.payload or b"") == ONLINE.encode():  # Home Assistant (re)started
                for b in self.boards.values():
                    b.publish_discovery(force=True)
            return
        if topic.endswith("/descriptor"):
            n = len(payload) if isinstance(payload, (bytes, bytearray)) else 0
            if n > INBOUND_BYTES_PER_TOKEN and not self.inbound.charge(n):
                return  # large ones share the commands' rate (a flood of them would hold the loop)
            self._note_descriptor(topic, msg.payload)
            return
        parsed = self.topics.parse_command(topic) or mission_topics.parse(self.topics, topic)
        if parsed is None:
            return
        key, op, channel = parsed
        if key not in self.boards and key in self.elsewhere:
            return  # a board of another service on this broker: that one answers
        self.inbound.offer((msg, key, op, channel), len(payload) if isinstance(payload, (bytes, bytearray)) else 0)

    async def _worker(self) -> None:
        while True:
            msg, key, op, channel = await self.inbound.get()
            try:
                await self._command(msg, key, op, channel)
            except asyncio.CancelledError:
                raise
            except Exception as e:  # noqa: BLE001 - one command's bug must not end the worker
                log.error("hubwire serve: MQTT: %s %s/%s: %s: %s", op, key, channel, type(e).__name__, e)

    async def _command(self, msg: aiomqtt.Message, key: str, op: str, channel: Optional[str]) -> None:
        payload = msg.payload if isinstance(msg.payload, (bytes, bytearray)) else str(msg.payload or "").encode()
        reply = Reply(self, msg.properties, key)
        if reply.refused is not None:
            await reply.error(op, channel, "BadRequest", reply.refused)
            return
        bb = self.boards.get(key)
        if bb is None:
            await reply.error(op, channel, "UnknownBoard",
                              f"no board {key!r}; boards: {', '.join(sorted(self.boards)) or 'none'}")
            return
        if op.startswith("mission:"):
            await mission_topics.command(self, bb, op, channel or "", bytes(payload), reply)
            return
        await bb.command(op, channel, bytes(payload), reply)

    def note_refusal(self, why: str, key: str) -> None:
        """Log a refused command: the first at once, then a count at most every DROP_LOG_INTERVAL_S."""
        self.refusals += 1
        now = asyncio.get_running_loop().time()
        if self._refusal_logged_at is None or now - self._refusal_logged_at >= DROP_LOG_INTERVAL_S:
            self._refusal_logged_at = now
            log.warning("hubwire serve: MQTT: BadRequest: %s; the command to %s was refused (%d refused so far)",
                        why, key, self.refusals)

    def reply_refusal(self, topic: str) -> Optional[str]:
        """Why the bridge will not publish a reply to ``topic`` (None: it will)."""
        shown = repr(topic[:80]) + ("..." if len(topic) > 80 else "")
        if not topic or any(c in topic for c in "+#\0"):
            return f"reply topic {shown} is empty or has a wildcard or NUL"
        try:
            n = len(topic.encode("utf-8"))
        except UnicodeEncodeError:
            return "reply topic is not valid UTF-8"
        if n > 65535:
            return "reply topic is too long"
        if not topic.startswith(self.reply_prefixes):
            return f"reply topic {shown} is outside {', '.join(self.reply_prefixes)} (the reply prefixes)"
        if self.topics.parse_command(topic) or mission_topics.parse(self.topics, topic) or topic.startswith(f"{self.topics.prefix}/_service/"):
            return f"reply topic {shown} is a command or status topic of the bridge"
        return None


    def _note_descriptor(self, topic: str, payload: Any) -> None:
        key = topic[len(self.topics.prefix) + 1:-len("/descriptor")]
        if key not in self.boards:
            ours = [(k, (b.board.name, b.board.board_id)) for k, b in self.boards.items() if b.board is not None]
            for t in self.retired.note(key, payload, ours):
                self.outbox.forget(t)
        try:
            service = json.loads(bytes(payload)).get("service") if payload else None
        except (ValueError, TypeError, AttributeError, RecursionError):  # RecursionError: nested too deep
            service = None
        if isinstance(service, str) and service != self.config.service_id and key not in self.boards:
            if len(self.elsewhere) >= MAX_ELSEWHERE and key not in self.elsewhere:
                self.elsewhere.pop(next(iter(self.elsewhere)))  # the oldest: its service answers UnknownBoard too
            self.elsewhere[key] = service
        else:
            self.elsewhere.pop(key, None)
        if isinstance(service, str) and service != self.config.service_id and key in self.boards:
            # two hubs each serve a board under this key: both would answer its commands
            log.error("hubwire serve: MQTT: board %r is also served by service %r on this broker; give one "
                      "of the boards another device name (each board key must be unique on a broker)",
                      key, service)
