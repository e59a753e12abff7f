"""Hub session: one serial link to one device (PROTOCOL.md §4).

A :class:`Session` owns the port and three kinds of threads:

- the **reader** thread reads the port, decodes frames, answers hellos, acks events, routes answers
  to the waiting callers and samples to streams, sends hellos and heartbeats on time, declares the
  link lost after silence and re-opens the port (with backoff) if it disappeared;
- the **dispatcher** thread runs application callbacks (events, link lost/restored, reconnect), so a
  callback may itself make calls on the device;
- a short-lived **discovery** thread fetches the descriptor after a device (re)boot.

Callers (any thread) make transactions (``R``, ``C``, ``J``, ``S``) through :meth:`request`,
:meth:`control` and :meth:`subscribe`. Controls are stop-and-wait: while one is unanswered no other
transaction is sent, so the device's duplicate detection is exact.
"""
from __future__ import annotations

import enum
import logging
import os
import queue
import random
import threading
import time
from collections import deque
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Callable, Deque, Dict, Iterator, List, Optional, Tuple

import serial

from .cache import DescriptorCache
from .descriptor import MAX_DESCRIPTOR_SIZE, Descriptor, parse_descriptor
from .errors import DescriptorError, HubwireError, InvalidValue, LinkLost, NakError, ProtocolVersionError, Timeout
from .wire import messages as m
from .wire.frame import Frame, FrameDecoder, encode_frame
from .wire.messages import NakCode

__all__ = ["State", "Session", "Event", "StreamSample", "LinkHealth"]

log = logging.getLogger("hubwire")

HELLO_INTERVAL = 0.1
READ_TIMEOUT = 0.01
CHUNK_WINDOW = 4
HUB_MAX_PAYLOAD = 255
#: events waiting in one dev.events() iterator; beyond it the oldest is dropped (and counted)
EVENT_QUEUE_LIMIT = 4096
#: callbacks waiting on the dispatcher; beyond it new events are not acked (the device retries them)
DISPATCH_LIMIT = 1024


class State(enum.Enum):
    """Hub link state: ``CONNECTING`` (handshake / discovery), ``READY``, ``LOST``, ``CLOSED``."""

    CONNECTING = "connecting"
    READY = "ready"
    LOST = "lost"
    CLOSED = "closed"


@dataclass(frozen=True)
class Event:
    """An event received from the device: channel ``name``, decoded ``value``, ``seq`` and arrival
    ``time`` (``time.monotonic()``)."""

    name: str
    value: Any
    seq: int
    time: float
    channel_id: int


@dataclass(frozen=True)
class StreamSample:
    """One streamed sample: ``value``, device-side ``since_ms`` since the previous sample, ``seq``
    (the subscription's sample counter) and ``lost`` (samples missed before this one, from seq gaps)."""

    value: Any
    since_ms: int
    seq: int
    lost: int
    time: float


@dataclass
class LinkHealth:
    """Snapshot of the link: state, ages in seconds and the error counters of both receivers.

    ``hub_counters`` are this hub's receiver counters (how well the hub hears the device);
    ``device_counters`` are the ones the device reported in its last heartbeat (how well it hears us).
    """

    state: str
    last_rx_age: Optional[float]
    heartbeat_age: Optional[float]
    device_heartbeats: int
    device_heartbeat_ms: Optional[int]
    hub_counters: Dict[str, int]
    device_counters: Dict[str, int]
    stats: Dict[str, int] = field(default_factory=dict)


class _Pending:
    __slots__ = ("type", "seq", "id", "wire", "answer", "error", "sent_at", "tries")

    def __init__(self, type: int, seq: int, id: int, wire: bytes) -> None:
        self.type = type
        self.seq = seq
        self.id = id
        self.wire = wire
        self.answer: Optional[Frame] = None
        self.error: Optional[BaseException] = None
        self.sent_at = 0.0
        self.tries = 0

    @property
    def done(self) -> bool:
        return self.answer is not None or self.error is not None


class _Gate:
    """Shared/exclusive gate: many R/J/S in flight, or one C alone (stop and wait)."""

    def __init__(self) -> None:
        self._cv = threading.Condition()
        self._shared = 0
        self._excl = False
        self._excl_waiting = 0

    @contextmanager
    def shared(self) -> Iterator[None]:
        with self._cv:
            while self._excl or self._excl_waiting:
                self._cv.wait()
            self._shared += 1
        try:
            yield
        finally:
            with self._cv:
                self._shared -= 1
                self._cv.notify_all()

    @contextmanager
    def exclusive(self) -> Iterator[None]:
        with self._cv:
            self._excl_waiting += 1
            try:
                while self._excl or self._shared:
                    self._cv.wait()
            finally:
                self._excl_waiting -= 1
            self._excl = True
        try:
            yield
        finally:
            with self._cv:
                self._excl = False
                self._cv.notify_all()


def _put_dropping_oldest(q: "queue.Queue[Any]", item: Any, stats: Dict[str, int]) -> None:
    """Put ``item``; if the (bounded) queue is full, drop its oldest entry first and count it."""
    while True:
        try:
            q.put_nowait(item)
            return
        except queue.Full:
            try:
                q.get_nowait()
                stats["events_dropped"] += 1
            except queue.Empty:
                pass


class _Subscription:
    """Hub-side record of one stream consumer."""

    def __init__(self, channel_id: int, interval_ms: int, maxlen: int) -> None:
        self.channel_id = channel_id
        self.interval_ms = interval_ms
        self.granted_ms = 0
        self.queue: Deque[Any] = deque(maxlen=maxlen)
        self.cv = threading.Condition()
        self.ended: Optional[BaseException] = None
        self.last_seq: Optional[int] = None
        self.dropped = 0

    def push(self, item: Any) -> None:
        with self.cv:
            if len(self.queue) == self.queue.maxlen:
                self.dropped += 1
            self.queue.append(item)
            self.cv.notify_all()

    def end(self, exc: BaseException) -> None:
        with self.cv:
            if self.ended is None:
                self.ended = exc
            self.cv.notify_all()


class Session:
    """One hub-side session with a device on a serial URL (see module docstring).

    Construct, then :meth:`open` (handshake + discovery); :meth:`close` when done. Thread-safe.

    Parameters: ``url`` (anything ``serial.serial_for_url`` accepts), ``baudrate``,
    ``connect_timeout`` (handshake deadline, s), ``heartbeat_ms`` (hub heartbeat interval),
    ``retry_timeout`` (s) and ``tries`` (per transaction), ``cache_dir`` (descriptor cache directory,
    ``None`` default, ``False`` disables), ``progress`` (``callable(received, total)`` during descriptor
    downloads), ``on_link_lost`` / ``on_link_restored`` / ``on_reconnect`` callbacks.
    """

    def __init__(
        self,
        url: str,
        baudrate: int = 115200,
        *,
        connect_timeout: float = 5.0,
        heartbeat_ms: int = 250,
        retry_timeout: float = 0.1,
        tries: int = 5,
        cache_dir: Any = None,
        progress: Optional[Callable[[int, int], None]] = None,
        on_link_lost: Optional[Callable[[], None]] = None,
        on_link_restored: Optional[Callable[[], None]] = None,
        on_reconnect: Optional[Callable[[Descriptor], None]] = None,
        serial_kwargs: Optional[Dict[str, Any]] = None,
    ) -> None:
        self.url = url
        self.baudrate = baudrate
        self.connect_timeout = connect_timeout
        self.heartbeat_ms = heartbeat_ms
        self.retry_timeout = retry_timeout
        self.tries = tries
        self.cache = DescriptorCache(cache_dir)
        self.progress = progress
        self._serial_kwargs = dict(serial_kwargs or {})
        #: this hub session's nonce: random per connection, never 0 (os.urandom: distinct across forks)
        self.nonce = int.from_bytes(os.urandom(4), "little") or 1

        self._lock = threading.RLock()
        self._cv = threading.Condition(self._lock)
        self._wlock = threading.Lock()
        self._gate = _Gate()
        self._port: Optional[Any] = None
        self._decoder = FrameDecoder(HUB_MAX_PAYLOAD)
        self._stop = threading.Event()
        self._reader: Optional[threading.Thread] = None

        self.state = State.CONNECTING
        self.device_hello: Optional[m.Hello] = None
        self.descriptor: Optional[Descriptor] = None
        self._descriptor_nonce: Optional[int] = None
        self._discovering = False
        self._discovery_error: Optional[BaseException] = None
        self._discovery_retry_at = 0.0
        self._fatal: Optional[BaseException] = None
        self._progress_at = 0.0
        self._linked = False
        self._hello_count = 0

        self._seq = random.randrange(256)
        self._pending: Dict[Tuple[int, int], _Pending] = {}
        self._last_rx = 0.0
        self._last_hello_tx = 0.0
        self._last_hb_tx = 0.0
        self._hb_counter = 0
        self._peer_hb_ms = 250
        self._peer_hb: Optional[m.Heartbeat] = None
        self._peer_hb_at: Optional[float] = None
        self._peer_hb_count = 0
        self._reopen_at = 0.0
        self._reopen_delay = 0.1
        self._last_event_seq: Optional[int] = None
        self._subs: Dict[int, List[_Subscription]] = {}
        self._event_queues: List["queue.Queue[Event]"] = []
        self._event_cbs: Dict[Optional[str], List[Callable[[Any], Any]]] = {}
        # events that arrived while nobody listened; handed to the first listener (bounded)
        self._backlog: Deque[Event] = deque(maxlen=1024)

        self._link_lost_cbs: List[Callable[[], Any]] = [on_link_lost] if on_link_lost else []
        self._link_restored_cbs: List[Callable[[], Any]] = [on_link_restored] if on_link_restored else []
        self._reconnect_cbs: List[Callable[[Descriptor], Any]] = [on_reconnect] if on_reconnect else []

        self._dispatch_q: "queue.Queue[Optional[Tuple[Callable[..., Any], Tuple[Any, ...]]]]" = queue.Queue()
        self._dispatcher: Optional[threading.Thread] = None
        #: counters for diagnostics and tests
        self.stats: Dict[str, int] = {
            "chunk_requests": 0, "retries": 0, "events": 0, "duplicate_events": 0, "reboots": 0,
            "link_lost": 0, "link_restored": 0, "rehandshakes": 0, "port_reopens": 0,
            "unknown_frames": 0, "unmatched_answers": 0, "cache_hits": 0, "downloads": 0, "samples": 0,
            "not_linked": 0, "events_deferred": 0, "events_dropped": 0,
        }
        #: test hook: when set, nothing is written to the port (simulates a silent hub)
        self.tx_paused = False
        #: test hook: ``tx_filter(wire_bytes) -> bool``; frames for which it returns False are not sent
        self.tx_filter: Optional[Callable[[bytes], bool]] = None
        #: test hook: ``rx_filter(frame) -> bool``; received frames for which it returns False are ignored
        self.rx_filter: Optional[Callable[[Frame], bool]] = None

    # ------------------------------------------------------------------------------ lifecycle

    def open(self) -> "Session":
        """Open the port, handshake and discover. Raises Timeout, ProtocolVersionError,
        DescriptorError or HubwireError (port cannot be opened)."""
        try:
            self._port = self._open_port()
        except (serial.SerialException, OSError, ValueError) as e:
            raise HubwireError(f"cannot open {self.url}: {e}") from e
        self._dispatcher = threading.Thread(target=self._dispatch_loop, name="hubwire-dispatch", daemon=True)
        self._dispatcher.start()
        self._reader = threading.Thread(target=self._read_loop, name=f"hubwire-reader {self.url}", daemon=True)
        self._reader.start()
        try:
            self._await_connected()
        except BaseException:
            self.close()
            raise
        return self

    def _open_port(self) -> Any:
        kw = {"timeout": READ_TIMEOUT, "write_timeout": 2.0}
        kw.update(self._serial_kwargs)
        port = serial.serial_for_url(self.url, baudrate=self.baudrate, **kw)
        try:
            port.reset_input_buffer()
        except Exception:  # noqa: BLE001 - not every URL handler supports it
            pass
        return port

    def _await_connected(self) -> None:
        deadline = time.monotonic() + self.connect_timeout
        with self._cv:
            while self.device_hello is None and self._fatal is None:
                left = deadline - time.monotonic()
                if left <= 0:
                    c = self._decoder.counters()
                    noise = "" if not any(c.values()) else (
                        f"; received only noise (dropped {c['dropped']}, crc {c['crc']}, overflow {c['overflow']})")
                    raise Timeout(f"no Hubwire device answered on {self.url} within {self.connect_timeout:g} s"
                                  f" (hello sent every {HELLO_INTERVAL * 1000:.0f} ms){noise}")
                self._cv.wait(left)
            # the handshake is done; discovery may take longer than the deadline as long as it makes
            # progress (a big descriptor on a slow line), but not connect_timeout without any
            self._progress_at = time.monotonic()
            while self.state is not State.READY and self._fatal is None:
                if self._discovery_error is not None:
                    raise self._discovery_error
                if self.state is State.CLOSED:
                    raise HubwireError("session closed while connecting")
                idle = time.monotonic() - self._progress_at
                if idle >= self.connect_timeout:
                    raise Timeout(f"device on {self.url} answered the handshake but its descriptor did not "
                                  f"arrive: no progress for {self.connect_timeout:g} s")
                self._cv.wait(min(0.5, self.connect_timeout - idle))
            if self._fatal is not None:
                raise self._fatal

    def close(self) -> None:
        """Cancel streams, stop the threads and close the port. Idempotent."""
        with self._cv:
            if self.state is State.CLOSED and self._reader is None:
                return
            ready = self.state is State.READY
        if ready:
            for cid in list(self._subs):
                try:
                    self._send_frame(m.SUBSCRIBE, self._next_seq(), cid, m.Subscribe(0).pack())
                except Exception:  # noqa: BLE001 - best effort
                    pass
        with self._cv:
            self.state = State.CLOSED
            self._fail_pending(LinkLost("session closed"))
            self._end_streams(LinkLost("session closed"))
            self._cv.notify_all()
        self._stop.set()
        if self._reader is not None and self._reader is not threading.current_thread():
            self._reader.join(2.0)
        self._reader = None
        port, self._port = self._port, None
        if port is not None:
            try:
                port.close()
            except Exception:  # noqa: BLE001
                pass
        self._dispatch_q.put(None)
        if self._dispatcher is not None and self._dispatcher is not threading.current_thread():
            self._dispatcher.join(2.0)
        for q in self._event_queues:
            _put_dropping_oldest(q, None, self.stats)

    # --------------------------------------------------------------------------- callbacks API

    def add_link_lost(self, cb: Callable[[], Any]) -> None:
        """Call ``cb()`` (on the dispatcher thread) when the link is lost."""
        self._link_lost_cbs.append(cb)

    def add_link_restored(self, cb: Callable[[], Any]) -> None:
        """Call ``cb()`` when the link is back (same device session, or a rebooted device)."""
        self._link_restored_cbs.append(cb)

    def add_reconnect(self, cb: Callable[[Descriptor], Any]) -> None:
        """Call ``cb(descriptor)`` after a rebooted device was handshaken and rediscovered."""
        self._reconnect_cbs.append(cb)

    def add_event_callback(self, name: Optional[str], cb: Callable[[Any], Any]) -> None:
        """Call ``cb(value)`` (``cb(event)`` when ``name`` is None: every event) on the dispatcher.

        Events that arrived earlier while nobody listened (see :meth:`event_queue`) are handed to
        the first listener that matches them.
        """
        with self._lock:
            self._event_cbs.setdefault(name, []).append(cb)
            if self._backlog:
                keep: Deque[Event] = deque(maxlen=self._backlog.maxlen)
                for ev in self._backlog:
                    if name is None:
                        self._dispatch(cb, ev)
                    elif ev.name == name:
                        self._dispatch(cb, ev.value)
                    else:
                        keep.append(ev)
                self._backlog = keep

    def remove_event_callback(self, name: Optional[str], cb: Callable[[Any], Any]) -> None:
        """Undo :meth:`add_event_callback`."""
        with self._lock:
            cbs = self._event_cbs.get(name, [])
            if cb in cbs:
                cbs.remove(cb)

    def event_queue(self, names: Optional[Any] = None) -> "queue.Queue[Event]":
        """A new queue receiving every event from now on (see :meth:`drop_event_queue`).

        Events acknowledged while no callback and no queue listened are kept (up to 1024) and put
        first into the next queue created (for the channel ``names`` it is meant for, if given), so
        none is lost between connect() and the first listener.
        """
        q: "queue.Queue[Event]" = queue.Queue(EVENT_QUEUE_LIMIT)
        with self._lock:
            self._event_queues.append(q)
            keep: Deque[Event] = deque(maxlen=self._backlog.maxlen)
            for ev in self._backlog:
                if names is None or ev.name in names:
                    _put_dropping_oldest(q, ev, self.stats)
                else:
                    keep.append(ev)
            self._backlog = keep
        return q

    def drop_event_queue(self, q: "queue.Queue[Event]") -> None:
        """Stop feeding a queue made by :meth:`event_queue`."""
        with self._lock:
            if q in self._event_queues:
                self._event_queues.remove(q)

    def _dispatch(self, fn: Callable[..., Any], *args: Any) -> None:
        self._dispatch_q.put((fn, args))

    def _dispatch_loop(self) -> None:
        while True:
            item = self._dispatch_q.get()
            if item is None:
                return
            fn, args = item
            try:
                fn(*args)
            except Exception:  # noqa: BLE001 - an application callback must not kill the hub
                log.exception("hubwire: callback %r raised", fn)

    # ---------------------------------------------------------------------------- health

    def health(self) -> LinkHealth:
        """Current :class:`LinkHealth`."""
        now = time.monotonic()
        with self._lock:
            hb = self._peer_hb
            return LinkHealth(
                state=self.state.value,
                last_rx_age=(now - self._last_rx) if self._last_rx else None,
                heartbeat_age=(now - self._peer_hb_at) if self._peer_hb_at is not None else None,
                device_heartbeats=self._peer_hb_count,
                device_heartbeat_ms=self.device_hello.heartbeat_ms if self.device_hello else None,
                hub_counters=self._decoder.counters(),
                device_counters={"crc": hb.crc, "overflow": hb.overflow, "dropped": hb.dropped} if hb else {},
                stats=dict(self.stats),
            )

    # ---------------------------------------------------------------------------- writing

    def _write(self, data: bytes) -> None:
        if self.tx_paused or (self.tx_filter is not None and not self.tx_filter(data)):
            return
        port = self._port
        if port is None:
            return
        try:
            with self._wlock:
                port.write(data)
        except (serial.SerialException, OSError) as e:
            log.debug("hubwire: write failed: %s", e)

    def _send_frame(self, type: int, seq: int, id: int, payload: bytes = b"") -> None:
        self._write(encode_frame(type, seq, id, payload))

    def _send_hello(self, reply: bool) -> None:
        h = m.Hello(m.PROTOCOL_VERSION, m.FLAG_REPLY if reply else 0, self.nonce, HUB_MAX_PAYLOAD, self.heartbeat_ms)
        self._last_hello_tx = time.monotonic()
        # a lone 00 first ends whatever noise the device may have collected (an empty frame is
        # ignored by the receiver, PROTOCOL.md 1), so this hello is not lost with it
        self._write(b"\x00" + encode_frame(m.HELLO, 0, 0, h.pack()))

    def _next_seq(self) -> int:
        with self._lock:
            self._seq = (self._seq + 1) & 0xFF
            return self._seq

    # ---------------------------------------------------------------------------- reader

    def _read_loop(self) -> None:
        while not self._stop.is_set():
            port = self._port
            if port is None:
                self._try_reopen()
                self._timers(time.monotonic())
                continue
            try:
                n = port.in_waiting
                data = port.read(n if n > 0 else 1)
            except (serial.SerialException, OSError, TypeError, AttributeError) as e:
                if self._stop.is_set():
                    return
                self._port_failed(e)
                continue
            if data:
                frames = self._decoder.feed(data)
                if frames:
                    now = time.monotonic()
                    flt = self.rx_filter
                    for f in frames:
                        if flt is not None and not flt(f):
                            continue
                        try:
                            self._handle(f, now)
                        except Exception:  # noqa: BLE001 - never let one frame kill the reader
                            log.exception("hubwire: error handling %r", f)
            self._timers(time.monotonic())

    def _port_failed(self, err: BaseException) -> None:
        log.info("hubwire: port %s failed: %s", self.url, err)
        port, self._port = self._port, None
        if port is not None:
            try:
                port.close()
            except Exception:  # noqa: BLE001
                pass
        self._decoder.reset()
        with self._cv:
            if self._linked or self.state is State.READY:
                self._declare_lost("port disappeared")
        self._reopen_delay = 0.1
        self._reopen_at = time.monotonic() + self._reopen_delay

    def _try_reopen(self) -> None:
        now = time.monotonic()
        if now < self._reopen_at:
            self._stop.wait(min(self._reopen_at - now, 0.05))
            return
        try:
            port = self._open_port()
        except (serial.SerialException, OSError, ValueError):
            self._reopen_delay = min(self._reopen_delay * 2, 2.0)
            self._reopen_at = time.monotonic() + self._reopen_delay
            return
        self.stats["port_reopens"] += 1
        # A re-opened port is a new connection: a new hub nonce (PROTOCOL.md 4.2). A board that lost
        # power mixes it into its own nonce, which is how its new boot is told from the old one.
        self.nonce = int.from_bytes(os.urandom(4), "little") or 1
        self._decoder.reset()
        self._port = port
        self._last_hello_tx = 0.0

    def _timers(self, now: float) -> None:
        with self._cv:
            state = self.state
            if state is State.CLOSED:
                return
            if self._linked:
                if now - self._last_rx > 4 * self._peer_hb_ms / 1000.0:
                    self._declare_lost(f"nothing heard for {(now - self._last_rx) * 1000:.0f} ms")
                    return
                if now - self._last_hb_tx >= self.heartbeat_ms / 1000.0:
                    self._send_heartbeat(now)
                dh = self.device_hello
                if (dh is not None and self._descriptor_nonce != dh.nonce and not self._discovering
                        and now >= self._discovery_retry_at):
                    self._start_discovery()
            elif self._fatal is None and now - self._last_hello_tx >= HELLO_INTERVAL:
                self._send_hello(reply=False)

    def _send_heartbeat(self, now: float) -> None:
        since = 0 if self._hb_counter == 0 else int((now - self._last_hb_tx) * 1000)
        self._hb_counter = (self._hb_counter + 1) & 0xFFFF
        d = self._decoder
        hb = m.Heartbeat(self._hb_counter, min(since, 0xFFFF), d.crc, d.overflow, d.dropped)
        self._last_hb_tx = now
        self._send_frame(m.HEARTBEAT, self._hb_counter & 0xFF, 0, hb.pack())

    def _declare_lost(self, why: str) -> None:
        # caller holds the lock
        was_up = self.state is State.READY or self._linked
        self._linked = False
        self._hb_counter = 0
        if self.state is not State.CLOSED:
            self.state = State.LOST if self.device_hello is not None else State.CONNECTING
        self._fail_pending(LinkLost(f"link to {self.url} lost ({why})"))
        self._end_streams(LinkLost(f"link to {self.url} lost ({why})"))
        self._last_hello_tx = 0.0
        self._cv.notify_all()
        if was_up:
            self.stats["link_lost"] += 1
            log.info("hubwire: link to %s lost (%s)", self.url, why)
            for cb in list(self._link_lost_cbs):
                self._dispatch(cb)

    def _fail_pending(self, exc: BaseException) -> None:
        for p in self._pending.values():
            if not p.done:
                p.error = exc
        self._cv.notify_all()

    def _end_streams(self, exc: BaseException) -> None:
        subs = [s for lst in self._subs.values() for s in lst]
        self._subs.clear()
        for s in subs:
            s.end(exc)

    # ------------------------------------------------------------------------ frame handling

    def _handle(self, f: Frame, now: float) -> None:
        t = f.type
        self._last_rx = now
        if t in (m.ACK, m.NAK, m.RESPONSE, m.CHUNK):
            with self._cv:
                p = self._pending.get((f.seq, f.id))
                if p is None or p.done:
                    self.stats["unmatched_answers"] += 1
                    return
                p.answer = f
                self._cv.notify_all()
            if t == m.NAK and f.payload[:1] == bytes((NakCode.NOT_LINKED,)):
                self._on_not_linked()
            return
        if t == m.SAMPLE:
            self._on_sample(f, now)
            return
        if t == m.HEARTBEAT:
            try:
                hb = m.Heartbeat.unpack(f.payload)
            except m.PayloadError:
                self._decoder.dropped += 1
                return
            with self._lock:
                self._peer_hb = hb
                self._peer_hb_at = now
                self._peer_hb_count += 1
            return
        if t == m.EVENT:
            self._on_event(f, now)
            return
        if t == m.HELLO:
            self._on_hello(f, now)
            return
        # unknown type or a request type the hub never answers: dropped and counted
        self._decoder.dropped += 1
        self.stats["unknown_frames"] += 1

    def _on_not_linked(self) -> None:
        # the device lost the link on its side: re-handshake (its hello reply relinks it)
        self.stats["not_linked"] += 1
        self._send_hello(reply=False)

    def _on_hello(self, f: Frame, now: float) -> None:
        try:
            h = m.Hello.unpack(f.payload)
        except m.PayloadError:
            self._decoder.dropped += 1
            return
        if not h.is_device:
            self._decoder.dropped += 1  # our own hello echoed back (loopback) or another hub
            return
        with self._cv:
            if h.version != m.PROTOCOL_VERSION:
                if self._fatal is None:
                    self._fatal = ProtocolVersionError(h.version, m.PROTOCOL_VERSION)
                    self._cv.notify_all()
                return
            if not h.is_reply:
                self._send_hello(reply=True)
            prev = self.device_hello
            was_linked = self._linked
            self.device_hello = h
            self._peer_hb_ms = h.heartbeat_ms or 250
            self._hello_count += 1
            self._linked = True
            self._last_rx = now
            if prev is None:
                self._last_hb_tx = 0.0
                self._cv.notify_all()
                return
            if prev.nonce != h.nonce or (prev.descriptor_hash, prev.descriptor_length) != (
                    h.descriptor_hash, h.descriptor_length):
                # the device rebooted: new session on its side (a changed descriptor with an
                # unchanged nonce means the same: new firmware on a board without nonce entropy)
                self.stats["reboots"] += 1
                log.info("hubwire: device on %s rebooted (nonce %08x -> %08x)", self.url, prev.nonce, h.nonce)
                self._last_event_seq = None
                self._descriptor_nonce = None  # rediscover (from the cache if the hash is known)
                self._fail_pending(LinkLost("device rebooted"))
                self._end_streams(LinkLost("device rebooted"))
                if self.state is State.READY:
                    # it was up but we had not noticed the reboot: report the loss too
                    self.stats["link_lost"] += 1
                    for cb in list(self._link_lost_cbs):
                        self._dispatch(cb)
                if self.state is not State.CLOSED:
                    self.state = State.CONNECTING
                self._last_hb_tx = 0.0
                self._discovery_retry_at = 0.0
                self._cv.notify_all()
                return
            if not was_linked:
                self._restored()
            elif not h.is_reply and self.state is State.READY:
                # the device declared the link lost on its side (we kept hearing it): it announced
                # itself, we answered, so it is linked again; its failsafes fired meanwhile
                self.stats["rehandshakes"] += 1
                self.stats["link_lost"] += 1
                self._end_streams(LinkLost("the device dropped the link (its subscriptions ended)"))
                for cb in list(self._link_lost_cbs):
                    self._dispatch(cb)
                self._restored()

    def _restored(self) -> None:
        # caller holds the lock; same device session as before
        self._last_hb_tx = 0.0
        if self._descriptor_nonce == self.device_hello.nonce:  # type: ignore[union-attr]
            self.state = State.READY
        else:
            self.state = State.CONNECTING
        self.stats["link_restored"] += 1
        log.info("hubwire: link to %s restored", self.url)
        for cb in list(self._link_restored_cbs):
            self._dispatch(cb)
        self._cv.notify_all()

    def _on_event(self, f: Frame, now: float) -> None:
        with self._lock:
            desc = self.descriptor
            ready = (desc is not None and self.device_hello is not None
                     and self._descriptor_nonce == self.device_hello.nonce)
            if not ready:
                return  # not acked: the device retries, we deliver it once we can decode it
            if self._dispatch_q.qsize() >= DISPATCH_LIMIT:
                # callbacks lag behind: not acked, so the device keeps it and retries (flow control)
                self.stats["events_deferred"] += 1
                return
            self._send_frame(m.ACK, f.seq, f.id)
            if self._last_event_seq == f.seq:
                self.stats["duplicate_events"] += 1
                return
            self._last_event_seq = f.seq
            self.stats["events"] += 1
            ch = desc.by_id(f.id)  # type: ignore[union-attr]
            if ch is None or not ch.is_event:
                log.warning("hubwire: event for unknown channel id %d", f.id)
                return
            try:
                value = ch.codec.decode(f.payload)
            except InvalidValue as e:
                log.warning("hubwire: malformed event %s: %s", ch.name, e)
                return
            ev = Event(ch.name, value, f.seq, now, f.id)
            named = self._event_cbs.get(ch.name, ())
            every = self._event_cbs.get(None, ())
            for cb in named:
                self._dispatch(cb, value)
            for cb in every:
                self._dispatch(cb, ev)
            for q in self._event_queues:
                _put_dropping_oldest(q, ev, self.stats)
            if not named and not every and not self._event_queues:
                self._backlog.append(ev)

    def _on_sample(self, f: Frame, now: float) -> None:
        self.stats["samples"] += 1
        with self._lock:
            subs = self._subs.get(f.id)
            desc = self.descriptor
            if not subs or desc is None:
                return
            ch = desc.by_id(f.id)
        if ch is None:
            return
        try:
            s = m.Sample.unpack(f.payload)
            value = ch.codec.decode(s.value)
        except (m.PayloadError, InvalidValue):
            self._decoder.dropped += 1
            return
        for sub in subs:
            lost = 0 if sub.last_seq is None else (f.seq - sub.last_seq - 1) & 0xFF
            sub.last_seq = f.seq
            sub.push(StreamSample(value, s.since_ms, f.seq, lost, now))

    # -------------------------------------------------------------------------- discovery

    def _start_discovery(self) -> None:
        # caller holds the lock
        self._discovering = True
        self._discovery_error = None
        hello = self.device_hello
        t = threading.Thread(target=self._discover, args=(hello,), name="hubwire-discovery", daemon=True)
        t.start()

    def _discover(self, hello: m.Hello) -> None:
        err: Optional[BaseException] = None
        desc: Optional[Descriptor] = None
        try:
            desc = self._load_descriptor(hello)
        except BaseException as e:  # noqa: BLE001 - reported to connect() or logged
            err = e
        with self._cv:
            self._discovering = False
            current = self.device_hello
            if err is not None:
                self._discovery_error = err
                self._discovery_retry_at = time.monotonic() + 1.0
                if not isinstance(err, LinkLost) and self.state is not State.CLOSED:
                    log.warning("hubwire: discovery on %s failed: %s", self.url, err)
                self._cv.notify_all()
                return
            key = (hello.nonce, hello.descriptor_hash, hello.descriptor_length)
            if current is None or (current.nonce, current.descriptor_hash, current.descriptor_length) != key:
                self._cv.notify_all()
                return  # rebooted again meanwhile; the timer starts a new discovery
            first = self.descriptor is None
            self.descriptor = desc
            self._descriptor_nonce = hello.nonce
            if self._linked:
                self.state = State.READY
            self._cv.notify_all()
            if not first:
                for cb in list(self._reconnect_cbs):
                    self._dispatch(cb, desc)

    def _load_descriptor(self, hello: m.Hello) -> Descriptor:
        if hello.descriptor_length > MAX_DESCRIPTOR_SIZE:
            raise DescriptorError(
                f"descriptor: the device announces {hello.descriptor_length} bytes, more than the hub's "
                f"limit of {MAX_DESCRIPTOR_SIZE} bytes (not downloaded)")
        cur = self.descriptor
        if cur is not None and cur.hash == hello.descriptor_hash and len(cur.raw) == hello.descriptor_length:
            self.stats["cache_hits"] += 1
            return cur
        cached = self.cache.get(hello.descriptor_hash, hello.descriptor_length)
        if cached is not None:
            try:
                d = parse_descriptor(cached)
                self.stats["cache_hits"] += 1
                return d
            except DescriptorError:
                pass
        last: Optional[BaseException] = None
        for _ in range(3):
            raw = self._download(hello)
            h = m.fnv1a32(raw)
            if h != hello.descriptor_hash:
                last = DescriptorError(
                    f"descriptor hash mismatch: device announced {hello.descriptor_hash:08x}, "
                    f"downloaded {len(raw)} bytes hash to {h:08x}")
                continue
            d = parse_descriptor(raw)
            self.cache.put(raw)
            return d
        assert last is not None
        raise last

    def _download(self, hello: m.Hello) -> bytes:
        """Fetch the descriptor with J requests, several in flight, lost chunks asked again."""
        total = hello.descriptor_length
        self.stats["downloads"] += 1
        if total == 0:
            return b""
        want = max(1, min(255, HUB_MAX_PAYLOAD - 4, hello.max_payload - 4))
        buf = bytearray(total)
        have = bytearray(total)  # 1 where received
        received = 0
        with self._gate.shared():
            inflight: Dict[int, _Pending] = {}  # offset -> pending
            next_off = 0
            gaps: Deque[int] = deque()
            try:
                while received < total:
                    now = time.monotonic()
                    with self._cv:
                        if self.state is State.CLOSED:
                            raise HubwireError("session closed")
                        if not self._linked:
                            raise LinkLost("link lost during descriptor download")
                        # fill the window
                        while len(inflight) < CHUNK_WINDOW and (gaps or next_off < total):
                            if gaps:
                                off = gaps.popleft()
                            else:
                                off = next_off
                                next_off += want
                            if off in inflight or have[off]:
                                continue
                            p = self._register(m.CHUNK, 0, m.ChunkRequest(off, want).pack())
                            inflight[off] = p
                            self.stats["chunk_requests"] += 1
                            self._transmit(p)
                        # harvest answers / retry
                        progressed = False
                        for off, p in list(inflight.items()):
                            if p.error is not None:
                                raise p.error
                            if p.answer is not None:
                                a = p.answer
                                if a.type == m.NAK and a.payload[:1] == bytes((NakCode.NOT_LINKED,)):
                                    # the device re-links on the hello this NAK triggered: ask again
                                    # when the retry timer fires (counts as a try)
                                    p.answer = None
                                    continue
                                del inflight[off]
                                self._unregister(p)
                                if a.type == m.NAK:
                                    code = a.payload[0] if a.payload else 0
                                    raise NakError(code, None, f"descriptor chunk at offset {off}")
                                try:
                                    c = m.Chunk.unpack(a.payload)
                                except m.PayloadError as e:
                                    raise DescriptorError(f"malformed descriptor chunk: {e}") from None
                                if c.total != total:
                                    raise DescriptorError(
                                        f"descriptor length changed: hello said {total}, chunk says {c.total}")
                                if c.offset != off or off + len(c.data) > total:
                                    raise DescriptorError(f"descriptor chunk for offset {c.offset} answers offset {off}")
                                if not c.data:
                                    raise DescriptorError(f"empty descriptor chunk at offset {off} of {total}")
                                for i, b in enumerate(c.data):
                                    if not have[off + i]:
                                        have[off + i] = 1
                                        buf[off + i] = b
                                        received += 1
                                self._progress_at = time.monotonic()
                                end = off + len(c.data)
                                if end < total and not have[end] and end not in inflight and len(c.data) < want:
                                    gaps.append(end)  # shorter answer than asked: fetch the rest
                                progressed = True
                            elif now - p.sent_at >= self.retry_timeout:
                                # Chunk requests are idempotent: on a lossy line keep asking for as
                                # long as the download as a whole makes progress (connect_timeout).
                                if now - self._progress_at >= self.connect_timeout:
                                    raise Timeout(f"descriptor chunk at offset {off} not answered after "
                                                  f"{p.tries} tries: no progress for {self.connect_timeout:g} s")
                                self.stats["retries"] += 1
                                self._transmit(p)
                        if progressed and self.progress is not None:
                            self._call_progress(received, total)
                        if not progressed and received < total:
                            waits = [p.sent_at + self.retry_timeout - now for p in inflight.values()]
                            self._cv.wait(max(0.001, min(waits)) if waits else 0.01)
                    if received < total and not inflight and not gaps and next_off >= total:
                        # holes left by short answers
                        for i in range(total):
                            if not have[i]:
                                gaps.append(i)
                                break
            finally:
                with self._cv:
                    for p in inflight.values():
                        self._unregister(p)
        return bytes(buf)

    def _call_progress(self, received: int, total: int) -> None:
        try:
            self.progress(received, total)  # type: ignore[misc]
        except Exception:  # noqa: BLE001
            log.exception("hubwire: progress callback raised")

    # ------------------------------------------------------------------------ transactions

    def _register(self, type: int, id: int, payload: bytes) -> _Pending:
        # caller holds the lock
        seq = self._next_seq()
        while (seq, id) in self._pending:
            seq = self._next_seq()
        p = _Pending(type, seq, id, encode_frame(type, seq, id, payload))
        self._pending[(seq, id)] = p
        return p

    def _unregister(self, p: _Pending) -> None:
        if self._pending.get((p.seq, p.id)) is p:
            del self._pending[(p.seq, p.id)]

    def _transmit(self, p: _Pending) -> None:
        p.tries += 1
        p.sent_at = time.monotonic()
        self._write(p.wire)

    def _check_ready(self, timeout: float) -> None:
        # caller holds the lock
        deadline = time.monotonic() + timeout
        while True:
            st = self.state
            if st is State.READY:
                return
            if st is State.CLOSED:
                raise HubwireError("session is closed")
            if st is State.LOST:
                raise LinkLost(f"link to {self.url} is down")
            left = deadline - time.monotonic()
            if left <= 0:
                extra = f": {self._discovery_error}" if self._discovery_error else ""
                raise Timeout(f"device on {self.url} is not ready (re-handshaking){extra}")
            self._cv.wait(left)

    def transact(self, type: int, id: int, payload: bytes = b"", *, timeout: Optional[float] = None,
                 what: str = "") -> Frame:
        """Send one transaction and return its answer (ACK, ``r``, ``J``); raise NakError on NAK.

        Retries with the same seq every ``retry_timeout`` up to ``tries`` times (Timeout after).
        Controls (``C``) are stop-and-wait: they run alone.
        """
        gate = self._gate.exclusive() if type == m.CONTROL else self._gate.shared()
        retry = self.retry_timeout if timeout is None else timeout / self.tries
        with gate:
            with self._cv:
                self._check_ready(max(self.connect_timeout, retry * self.tries))
                p = self._register(type, id, payload)
                try:
                    self._transmit(p)
                    while True:
                        if p.error is not None:
                            raise p.error
                        a = p.answer
                        if a is not None:
                            if a.type == m.NAK:
                                code = a.payload[0] if a.payload else 0
                                if code == NakCode.NOT_LINKED and p.tries < self.tries:
                                    # the device re-links on our hello; ask again (not applied yet)
                                    p.answer = None
                                    count = self._hello_count
                                    end = time.monotonic() + retry
                                    while self._hello_count == count and time.monotonic() < end and p.error is None:
                                        self._cv.wait(end - time.monotonic())
                                    self.stats["retries"] += 1
                                    self._transmit(p)
                                    continue
                                raise NakError(code, what or None)
                            return a
                        left = p.sent_at + retry - time.monotonic()
                        if left <= 0:
                            if p.tries >= self.tries:
                                raise Timeout(f"no answer from the device on {self.url}"
                                              f"{' for ' + what if what else ''} after {p.tries} tries")
                            self.stats["retries"] += 1
                            self._transmit(p)
                            continue
                        self._cv.wait(left)
                finally:
                    self._unregister(p)

    def request(self, id: int, *, timeout: Optional[float] = None, what: str = "") -> bytes:
        """``R``: read a channel; returns the ``r`` payload."""
        a = self.transact(m.REQUEST, id, b"", timeout=timeout, what=what)
        if a.type != m.RESPONSE:
            raise HubwireError(f"unexpected answer type 0x{a.type:02x} to a read of {what or id}")
        return a.payload

    def control(self, id: int, payload: bytes, *, timeout: Optional[float] = None, what: str = "") -> Frame:
        """``C``: write or call; returns the ACK or ``r`` frame."""
        return self.transact(m.CONTROL, id, payload, timeout=timeout, what=what)

    def subscribe(self, id: int, interval_ms: int, *, timeout: Optional[float] = None, what: str = "") -> int:
        """``S``: (re)subscribe or cancel (0); returns the granted interval."""
        a = self.transact(m.SUBSCRIBE, id, m.Subscribe(interval_ms).pack(), timeout=timeout, what=what)
        if a.type != m.ACK:
            raise HubwireError(f"unexpected answer type 0x{a.type:02x} to a subscribe")
        return m.SubscribeAck.unpack(a.payload).granted_ms if len(a.payload) >= 2 else interval_ms

    # ---------------------------------------------------------------------------- streams

    def open_stream(self, id: int, interval_ms: int, maxlen: int = 1024, what: str = "") -> _Subscription:
        """Subscribe and return a hub-side subscription whose queue receives :class:`StreamSample`."""
        sub = _Subscription(id, interval_ms, maxlen)
        with self._lock:
            others = self._subs.get(id, [])
            self._subs.setdefault(id, []).append(sub)
            interval = min([s.interval_ms for s in others] + [interval_ms])
        try:
            sub.granted_ms = self.subscribe(id, interval, what=what)
        except BaseException:
            self._remove_sub(sub)
            raise
        return sub

    def _remove_sub(self, sub: _Subscription) -> List[_Subscription]:
        with self._lock:
            lst = self._subs.get(sub.channel_id, [])
            if sub in lst:
                lst.remove(sub)
            if not lst:
                self._subs.pop(sub.channel_id, None)
            return list(lst)

    def close_stream(self, sub: _Subscription, wait: bool = True) -> None:
        """End a subscription; cancels it on the device when it was the channel's last consumer."""
        remaining = self._remove_sub(sub)
        sub.end(StopIteration())
        if self.state is not State.READY:
            return
        interval = min(s.interval_ms for s in remaining) if remaining else 0
        if wait:
            try:
                self.subscribe(sub.channel_id, interval)
            except HubwireError:
                pass
        else:
            self._send_frame(m.SUBSCRIBE, self._next_seq(), sub.channel_id, m.Subscribe(interval).pack())
