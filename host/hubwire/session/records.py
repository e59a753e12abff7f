"""Plain records the session hands out: link state, received events, stream samples, health, stats."""
from __future__ import annotations

import enum
from dataclasses import asdict, dataclass, field
from typing import Any, Dict, Optional

__all__ = ["State", "ReceivedEvent", "StreamSample", "LinkHealth", "Stats"]


class State(enum.Enum):
    """Hub link state: ``CONNECTING`` (handshake / discovery), ``READY``, ``LOST``, ``CLOSED``."""

    CONNECTING = "connecting"
    READY = "ready"
    LOST = "lost"
    CLOSED = "closed"


@dataclass(frozen=True)
class ReceivedEvent:
    """An event received from the device: channel ``name``, decoded ``value``, ``seq`` and arrival
    ``time``: when the hub received it, in seconds of ``time.monotonic()`` (a clock that only
    counts up, for intervals; not the time of day: take ``time.time()`` on receipt for that)."""

    name: str
    value: Any
    seq: int
    time: float
    channel_id: int


@dataclass(frozen=True)
class StreamSample:
    """One streamed sample: ``value``, device-side ``since_ms`` since the previous sample, ``seq``
    (the subscription's sample counter), ``lost`` (samples missed before this one, from seq gaps),
    arrival ``time`` in seconds of ``time.monotonic()`` (for intervals, not the time of day) and ``gap``: the link outages (losses, device reboots)
    between the previous sample and this one, which the hub rode through by subscribing again.
    ``gap`` is 0 normally; when it is not, ``lost`` is 0 (the device counts its samples afresh) and
    how long the outage lasted is the difference of ``time`` with the previous sample."""

    value: Any
    since_ms: int
    seq: int
    lost: int
    time: float
    gap: int = 0


@dataclass
class Stats:
    """Counters of one session, for diagnostics and tests."""

    chunk_requests: int = 0
    retries: int = 0
    events: int = 0
    duplicate_events: int = 0
    reboots: int = 0
    link_lost: int = 0
    link_restored: int = 0
    rehandshakes: int = 0
    port_reopens: int = 0
    unknown_frames: int = 0
    unmatched_answers: int = 0
    cache_hits: int = 0
    downloads: int = 0
    samples: int = 0
    not_linked: int = 0
    events_deferred: int = 0
    events_dropped: int = 0
    resubscribes: int = 0
    # hub channels (the device reads, writes, calls the hub; the hub sends it events)
    device_reads: int = 0
    device_writes: int = 0
    device_calls: int = 0
    device_duplicates: int = 0
    device_refused: int = 0
    device_unanswered: int = 0
    device_answers_dropped: int = 0  # a handler finished after the device gave up on its transaction
    binds_sent: int = 0
    bind_retries: int = 0
    hub_events_delivered: int = 0
    hub_events_refused: int = 0
    hub_events_skipped: int = 0
    hub_event_retries: int = 0
    # missions: updates delivered, repeats acked again, updates of runs this hub does not know
    mission_updates: int = 0
    duplicate_mission_updates: int = 0
    unknown_mission_updates: int = 0

    def as_dict(self) -> Dict[str, int]:
        """The counters as a plain dict (a snapshot)."""
        return asdict(self)


@dataclass
class LinkHealth:
    """Snapshot of the link: state, ages in seconds and the error counters of both receivers.

    ``hub_counters`` are this hub's receiver counters (how well the hub hears the device);
    ``device_counters`` are the ones the device reported in its last heartbeat (how well it hears us).
    ``device_heartbeat_ms`` is the interval the device announced, ``measured_heartbeat_ms`` the one it
    measured: the ms since its previous heartbeat carried by its latest one (None until measured: before
    any, and after the first one of a device start, which has no previous one).
    ``hub_heartbeat_ms`` and ``hub_heartbeat_since_ms`` are the same of this hub's own heartbeats.
    """

    state: str
    last_rx_age: Optional[float]
    heartbeat_age: Optional[float]
    device_heartbeats: int
    device_heartbeat_ms: Optional[int]
    hub_counters: Dict[str, int]
    device_counters: Dict[str, int]
    stats: Dict[str, int] = field(default_factory=dict)
    measured_heartbeat_ms: Optional[int] = None
    hub_heartbeat_ms: Optional[int] = None
    hub_heartbeat_since_ms: Optional[int] = None
