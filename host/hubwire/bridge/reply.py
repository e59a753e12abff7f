"""Where the answer to one MQTT command goes (docs/MQTT.md "Commands and replies"): only under the
bridge's reply prefixes, whatever topic the sender named."""
from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any, Dict, Optional

from paho.mqtt.packettypes import PacketTypes
from paho.mqtt.properties import Properties

from .topics import dumps

if TYPE_CHECKING:
    from .mqtt import Bridge

__all__ = ["Reply"]


class Reply:
    """Where the answer to one command goes: the MQTT 5 response topic (with its correlation data),
    the ``reply_to`` of an ``rpc`` envelope (MQTT 3.1.1 clients), or, for errors only, the board's
    ``error`` topic."""

    def __init__(self, bridge: "Bridge", props: Optional[Properties], key: str) -> None:
        self.bridge = bridge
        self.key = key
        self.topic: Optional[str] = getattr(props, "ResponseTopic", None) if props is not None else None
        self.correlation: Optional[bytes] = getattr(props, "CorrelationData", None) if props is not None else None
        self.rpc_id: Any = None
        self.is_rpc = False
        #: why the reply topic the sender named is refused (the command is not carried out)
        self.refused: Optional[str] = None
        self._check()

    def _check(self) -> None:
        if self.topic is not None:
            self.refused = self.bridge.reply_refusal(self.topic)
            if self.refused is not None:
                self.topic = None  # the refusal goes to the board's error topic
                self.bridge.note_refusal(self.refused, self.key)

    def envelope(self, reply_to: Any, rpc_id: Any) -> None:
        self.is_rpc = True
        self.rpc_id = rpc_id
        if self.topic is None and self.refused is None:
            self.topic = self.bridge.topics.rpc_reply(self.key) if reply_to is None else str(reply_to)
            self._check()

    async def send(self, body: Dict[str, Any]) -> None:
        if self.is_rpc:
            body = {"id": self.rpc_id, **body}
        if self.topic is None:
            if body.get("ok") is False:
                await self.bridge.send(self.bridge.topics.errors(self.key), _dumps(body), qos=1)
            return
        props = None
        if self.correlation is not None:
            props = Properties(PacketTypes.PUBLISH)  # type: ignore[no-untyped-call]
            props.CorrelationData = self.correlation
        await self.bridge.send(self.topic, _dumps(body), qos=1, properties=props)

    async def ok(self, **fields: Any) -> None:
        await self.send({"ok": True, **fields})

    async def error(self, op: str, channel: Optional[str], kind: str, message: str, **extra: Any) -> None:
        await self.send({"ok": False, "op": op, "channel": channel, "error": kind, "message": message, **extra})


def _dumps(body: Dict[str, Any]) -> str:
    """A reply as JSON; text that is not valid Unicode (a lone surrogate in an ``id``) escaped."""
    text = dumps(body)
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        text = json.dumps(body, separators=(",", ":"), allow_nan=False)
    return text
