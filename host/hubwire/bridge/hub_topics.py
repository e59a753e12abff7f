"""Hub channels backed from MQTT (``hubwire serve --mqtt HOST --mqtt-hub PATTERN``; docs/MQTT.md
"Hub channels"): for every hub channel of a board whose ``<board key>/<channel>`` matches a pattern
and that no client provides, the service answers the board from the broker:

| topic | retained | what |
| --- | --- | --- |
| `<prefix>/<key>/hub` | yes | the board's hub channels: who provides each, and the binding (JSON) |
| `<prefix>/<key>/hub/<channel>` | yes | the value: what the board reads (set below), writes, or was last sent as an event |
| `<prefix>/<key>/hub/<channel>/set` | no | JSON value: the value the board reads (`r`), or an event to send (`e`) |
| `<prefix>/<key>/hub/<channel>/call` | no | each call of a hub action by the board: `{"event_type", "arg"}` |

A value the board reads is offered once one is known (from `set`, or its retained value topic when
the service starts again): until then the channel is not declared, and the board is unbound for it.
A hub action answers the board at once (a `bool` result is True once the call is handed to the
broker); an action with another result type is not backed from MQTT. The bridge has a connection
of its own to the broker (client id ``hubwire-<service id>-hub``).
"""
from __future__ import annotations

import asyncio
import fnmatch
import logging
import ssl
from typing import Any, Dict, List, Optional, Sequence, Set, Tuple

import aiomqtt

from ..text import clip
from .hub_ha import hub_discovery
from ..daemon.hub_providers import HubConflict, HubProviders, Provider, entry_of
from .topics import BadPayload, Topics, dumps, level, parse_value, to_json

__all__ = ["HubBridge", "run_hub_bridge", "MAX_PAYLOAD"]

log = logging.getLogger("hubwire.mqtt")

#: the largest command payload taken, bytes (a hub value is at most 65,535 bytes on the wire)
MAX_PAYLOAD = 256 * 1024
#: messages waiting for the bridge; aiomqtt drops what finds the queue full
QUEUE = 256
#: seconds between attempts to reach the broker
RECONNECT_S = 1.0
#: conflicts remembered so that each is logged once (beyond it they are forgotten, and logged again)
MAX_CONFLICTS_LOGGED = 1024


class HubBridge(Provider):
    """The MQTT side of hub channels: a :class:`Provider` whose values come from the broker."""

    kind = "mqtt"

    def __init__(self, fleet: Any, host: str, port: int, patterns: Sequence[str], *, prefix: str = "hubwire",
                 discovery_prefix: Optional[str] = "homeassistant", service_id: str = "hubwire",
                 username: Optional[str] = None, password: Optional[str] = None,
                 tls_context: Optional[ssl.SSLContext] = None) -> None:
        self.topics = Topics(prefix, discovery_prefix)
        super().__init__(f"MQTT ({self.topics.prefix}/<board>/hub/<channel>/set on {host}:{port})")
        self.fleet = fleet
        self.registry: HubProviders = fleet.hub
        self.host, self.port = host, port
        self.patterns = list(patterns)
        self.service_id = service_id
        self.username, self.password, self.tls_context = username, password, tls_context
        #: values the boards read, per (board key, channel); one per hub channel of a known board
        self.values: Dict[Tuple[str, str], Any] = {}
        #: retained messages to publish (topic -> payload), kept while the broker is away
        self.latest: Dict[str, str] = {}
        self.client: Optional[aiomqtt.Client] = None
        self.connected = asyncio.Event()
        self._wake = asyncio.Event()
        self._conflicts: Set[Tuple[str, str, str]] = set()
        #: what this connection published, retained (cleared at each connect: all go out again)
        self._published: Dict[str, str] = {}
        self._dirty: Set[str] = set()

    # ------------------------------------------------------------------------- which channels

    def backs(self, key: str, name: str) -> bool:
        return any(fnmatch.fnmatchcase(f"{key}/{name}", p) for p in self.patterns)

    def _channels(self, key: str) -> List[Any]:
        try:
            desc = self.fleet.descriptor(key)
        except KeyError:
            return []
        out = []
        for exp in desc.hub:
            if not self.backs(key, exp.name):
                continue
            if "c" in exp.access and exp.returns is not None and exp.returns.kind != "void" and \
                    exp.returns.type_obj.get("t") != "bool":
                continue  # no answer to give from MQTT
            out.append(exp)
        return out

    def sync(self, key: str) -> None:
        """Hold every backed channel of ``key`` nobody else holds; log a conflict once."""
        for exp in self._channels(key):
            if "e" in exp.access:
                continue
            holder = self.registry.holder(key, exp.name)
            if holder is self:
                continue
            try:
                self.registry.claim(key, self, [entry_of(exp)])
            except HubConflict as e:
                mark = (key, exp.name, holder.label if holder is not None else "")
                if mark not in self._conflicts:
                    if len(self._conflicts) >= MAX_CONFLICTS_LOGGED:
                        self._conflicts.clear()  # (each is logged again, at worst)
                    self._conflicts.add(mark)
                    log.error("hubwire serve: MQTT: %s", e)
            except Exception as e:  # noqa: BLE001 - a channel that cannot be declared stays unbound
                log.warning("hubwire serve: MQTT: hub channel %s of %s not backed: %s", exp.name, key, clip(str(e), 200))
        self._publish_board(key)

    def _changed(self, key: str) -> None:
        """The registry changed for ``key`` (a client came or went): try again, republish."""
        if key not in self._dirty:
            self._dirty.add(key)
            asyncio.get_running_loop().call_soon(self._resync, key)

    def _resync(self, key: str) -> None:
        self._dirty.discard(key)
        self.sync(key)

    # ------------------------------------------------------------------ answering the board

    def ready(self, key: str, name: str) -> bool:
        exp = self._exp(key, name)
        return exp is None or "r" not in exp.access or (key, name) in self.values

    def _exp(self, key: str, name: str) -> Any:
        try:
            return next((c for c in self.fleet.descriptor(key).hub if c.name == name), None)
        except KeyError:
            return None

    async def read(self, key: str, name: str) -> Any:
        return self.values[(key, name)]

    async def write(self, key: str, name: str, value: Any) -> Any:
        exp = self._exp(key, name)
        if "r" in exp.access:
            self.values[(key, name)] = value
        self._retain(self._value_topic(key, name), dumps(to_json(exp, value)))
        return True

    async def call(self, key: str, name: str, arg: Any) -> Any:
        exp = self._exp(key, name)
        client = self.client
        if client is None:
            raise aiomqtt.MqttError("the broker is away")
        body = {"event_type": name, "arg": None if exp.codec.kind == "void" else to_json(exp, arg)}
        await client.publish(self._value_topic(key, name) + "/call", dumps(body), qos=1)
        return True if exp.returns is not None and exp.returns.kind != "void" else None

    # ---------------------------------------------------------------------------- publishing

    def _value_topic(self, key: str, name: str) -> str:
        return self.topics.board(key, "hub", level(name))

    def _retain(self, topic: str, payload: str) -> None:
        if self._published.get(topic) == payload and topic not in self.latest:
            return  # the broker has it (a status or config republished unchanged)
        self.latest[topic] = payload
        self._wake.set()

    def _publish_board(self, key: str) -> None:
        rows = self.registry.status(key)
        if not rows:
            return  # a board that uses no hub channel
        self._retain(self.topics.board(key, "hub"), dumps({"channels": rows}))
        names = [e.name for e in self._channels(key)]
        if self.topics.discovery_prefix and names:
            b = self.fleet.get(key)
            for topic, payload in hub_discovery(self.topics, self.service_id, key, self.fleet.descriptor(key),
                                                b.board_id, names):
                self._retain(topic, payload)

    async def _publisher(self, client: aiomqtt.Client) -> None:
        while True:
            await self._wake.wait()
            self._wake.clear()
            while self.latest:
                topic = next(iter(self.latest))
                payload = self.latest.pop(topic)
                try:
                    await client.publish(topic, payload, qos=1, retain=True)
                except aiomqtt.MqttError:
                    self.latest.setdefault(topic, payload)
                    raise
                self._published[topic] = payload

    # ----------------------------------------------------------------------------- commands

    def on_message(self, msg: aiomqtt.Message) -> None:
        payload = msg.payload if isinstance(msg.payload, (bytes, bytearray)) else b""
        if len(payload) > MAX_PAYLOAD:
            return
        head = self.topics.prefix + "/"
        topic = str(msg.topic)
        parts = topic[len(head):].split("/") if topic.startswith(head) else []
        if len(parts) not in (3, 4) or parts[1] != "hub" or (len(parts) == 4 and parts[3] != "set"):
            return
        key, lvl = parts[0], parts[2]
        try:
            self.fleet.get(key)
            desc = self.fleet.descriptor(key)
        except KeyError:
            return  # a board this service does not serve
        exp = next((c for c in desc.hub if level(c.name) == lvl), None)
        if exp is None or not self.backs(key, exp.name):
            return
        try:
            if len(parts) == 3:  # a retained value: what the board read before the service restarted
                if msg.retain and "r" in exp.access and (key, exp.name) not in self.values:
                    self._take(key, exp, bytes(payload))
                return
            if "e" in exp.access:
                if not msg.retain:  # a retained command would send the event again at every connect
                    self._notify(key, exp, bytes(payload))
            elif "r" in exp.access:
                self._take(key, exp, bytes(payload))
        except (BadPayload, ValueError, TypeError) as e:
            log.warning("hubwire serve: MQTT: %s: %s", clip(topic, 120), clip(str(e), 200))

    def _value(self, exp: Any, payload: bytes) -> Any:
        return exp.check(exp.codec.from_json(parse_value(payload)))

    def _take(self, key: str, exp: Any, payload: bytes) -> None:
        value = self._value(exp, payload)
        was_ready = (key, exp.name) in self.values
        self.values[(key, exp.name)] = value
        self._retain(self._value_topic(key, exp.name), dumps(to_json(exp, value)))
        if not was_ready:
            self.registry.refresh(key)  # now it has a value: declared to the board

    def _notify(self, key: str, exp: Any, payload: bytes) -> None:
        from ..daemon import durable_ops

        value = self._value(exp, payload)
        durable_ops.notify(self.fleet, {"board": key, "channel": exp.name, "value": value})
        self._retain(self._value_topic(key, exp.name), dumps(to_json(exp, value)))

    # ----------------------------------------------------------------------------- running

    async def run(self) -> None:
        remove = self.registry.watch(self._changed)
        watcher = asyncio.get_running_loop().create_task(self._watch_fleet())
        try:
            while True:
                try:
                    await self._session()
                except aiomqtt.MqttError as e:
                    log.info("hubwire serve: MQTT (hub channels): broker %s:%d: %s", self.host, self.port, e)
                self.client = None
                self.connected.clear()
                await asyncio.sleep(RECONNECT_S)
        finally:
            remove()
            watcher.cancel()
            self.registry.release(self)

    async def _watch_fleet(self) -> None:
        for b in self.fleet.boards():
            self.sync(b.key)
        async for b in self.fleet.changes():
            self.sync(b.key)

    async def _session(self) -> None:
        async with aiomqtt.Client(self.host, self.port, identifier=f"hubwire-{self.service_id}-hub",
                                  protocol=aiomqtt.ProtocolVersion.V5, clean_start=True,
                                  username=self.username, password=self.password, tls_context=self.tls_context,
                                  max_queued_incoming_messages=QUEUE) as client:
            self.client = client
            self._published.clear()
            base = f"{self.topics.prefix}/+/hub/+"
            await client.subscribe(base, qos=1)
            await client.subscribe(base + "/set", qos=1)
            for b in self.fleet.boards():
                self._publish_board(b.key)
            for (key, name), value in list(self.values.items()):
                exp = self._exp(key, name)
                if exp is not None:
                    self._retain(self._value_topic(key, name), dumps(to_json(exp, value)))
            self._wake.set()
            publisher = asyncio.get_running_loop().create_task(self._publisher(client))
            self.connected.set()
            try:
                async for msg in client.messages:
                    self.on_message(msg)
            finally:
                publisher.cancel()


async def run_hub_bridge(fleet: Any, host: str, port: int, patterns: Sequence[str], **kw: Any) -> None:
    """Publish each board's hub status on the broker at ``host:port``, and back the hub channels
    matching ``patterns`` (``fnmatch`` on ``<board key>/<channel>``) from it, until cancelled."""
    await HubBridge(fleet, host, port, patterns, **kw).run()


def hub_bridge_task(broker: Any, patterns: Sequence[str]) -> Any:
    """``hubwire serve --mqtt``: the hub side of the bridge as one more task on the fleet."""
    kw: Dict[str, Any] = {"username": broker.username, "password": broker.password,
                          "tls_context": broker.tls_context()}
    if broker.service_id:
        kw["service_id"] = broker.service_id

    async def run(fleet: Any) -> None:
        if "service_id" not in kw:
            from .topics import BridgeConfig

            kw["service_id"] = BridgeConfig().service_id  # as the bridge's own default
        await run_hub_bridge(fleet, broker.host, broker.effective_port, patterns, **kw)
    return run
