"""Hub session: one link to one device (PROTOCOL.md §4), split by responsibility.

- :mod:`.link`: transport, framing, hello handshake, heartbeats, loss detection, re-opening;
- :mod:`.discovery`: the descriptor, from the cache or downloaded in a window of chunk requests;
- :mod:`.transactions`: requests matched to answers, retries, stop-and-wait controls;
- :mod:`.events`: acks, deduplication, backlog, bounded queues;
- :mod:`.streams`: subscriptions shared by several consumers, seq gaps;
- :mod:`.hub_channels`, :mod:`.hub_answers`: the hub's own channels (bind report, hub events, the
  device's R / C / J);
- :mod:`.core`: the state machine tying them together on one asyncio event loop;
- :mod:`.facade`: :class:`Session`, the synchronous facade; :mod:`.runner`: its loop thread.
"""
from .core import SessionCore
from .events import DISPATCH_LIMIT, EVENT_QUEUE_LIMIT
from .facade import Session
from .link import HELLO_INTERVAL, HUB_MAX_PAYLOAD
from .records import LinkHealth, ReceivedEvent, State, Stats, StreamSample
from .streams import AsyncSubscription, Subscription, ThreadSubscription

__all__ = ["Session", "SessionCore", "State", "ReceivedEvent", "StreamSample", "LinkHealth", "Stats",
           "Subscription", "ThreadSubscription", "AsyncSubscription", "HELLO_INTERVAL", "HUB_MAX_PAYLOAD",
           "EVENT_QUEUE_LIMIT", "DISPATCH_LIMIT"]
