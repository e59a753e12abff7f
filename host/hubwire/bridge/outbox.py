"""What the bridge has to tell the broker, kept across broker outages.

Two kinds of message survive an outage, each the way its promise needs:

- **last values** (retained: descriptors, link states, channel states, discovery configs): one per
  topic, the newest wins; all of them are published again after every reconnect, so a broker that
  lost its retained store (restarted without persistence) gets them back;
- **events** (QoS 1, in order): kept until the broker acknowledged them (PUBACK); one not
  acknowledged when the connection dropped is sent again after the reconnect, with the same event
  id, which is how subscribers drop the rare duplicate.

Stream samples and replies are not kept: they go out only while connected (docs/MQTT.md).
"""
from __future__ import annotations

import asyncio
from collections import OrderedDict, deque
from typing import Deque, Dict, Optional, Tuple

__all__ = ["Outbox"]


class Outbox:
    def __init__(self, event_limit: int = 10000) -> None:
        self.latest: Dict[str, str] = {}
        self.dirty: "OrderedDict[str, None]" = OrderedDict()
        self.events: Deque[Tuple[str, str]] = deque()
        self.event_limit = event_limit
        #: events dropped because more than ``event_limit`` waited for the broker
        self.events_dropped = 0
        self.wake = asyncio.Event()

    def put_latest(self, topic: str, payload: str) -> None:
        """Retain ``payload`` on ``topic`` (an empty payload clears the retained message)."""
        if self.latest.get(topic) == payload and topic not in self.dirty:
            return
        self.latest[topic] = payload
        self.dirty[topic] = None
        self.wake.set()

    def forget(self, topic: str) -> None:
        """Clear ``topic`` on the broker once, then stop republishing it."""
        self.put_latest(topic, "")

    def put_event(self, topic: str, payload: str) -> None:
        if len(self.events) >= self.event_limit:
            self.events.popleft()
            self.events_dropped += 1
        self.events.append((topic, payload))
        self.wake.set()

    def all_dirty(self) -> None:
        """After a reconnect: every last value is published again."""
        self.dirty = OrderedDict((t, None) for t in self.latest)
        self.wake.set()

    def take_latest(self) -> Optional[Tuple[str, str]]:
        if not self.dirty:
            return None
        topic, _ = self.dirty.popitem(last=False)
        payload = self.latest[topic]
        if payload == "":
            del self.latest[topic]  # cleared once; nothing to republish
        return topic, payload

    def requeue_latest(self, topic: str, payload: str) -> None:
        """A last value whose publish failed: publish it again after the reconnect."""
        if topic not in self.latest:
            self.latest[topic] = payload
        self.dirty[topic] = None
