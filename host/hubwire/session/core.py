"""The session core: one device's link, discovery, transactions, events and streams on one asyncio
event loop, and the state machine tying them together (PROTOCOL.md §4).

It runs entirely on its loop (no locks): the transport calls it when bytes arrive, loop timers
drive hellos, heartbeats and loss detection, and callers await its coroutines. Application
callbacks go through ``dispatch`` (a thread of their own for the synchronous API).
"""
from __future__ import annotations

import asyncio
import logging
import threading
import time
from typing import Any, Callable, List, Optional, Tuple

from ..descriptor.cache import DescriptorCache
from ..descriptor import Descriptor
from ..diagnose import PortOpenError, no_answer_message
from ..errors import HubwireError, LinkLost, ProtocolVersionError, Timeout
from ..hub import HubChannels
from ..transport import Transport
from ..wire import messages as m
from ..wire.frame import Frame
from ..wire.messages import NakCode
from .discovery import Discovery
from .events import Events
from .hub_channels import HubSide
from .link import HELLO_INTERVAL, HelloOutcome, Link
from .missions import Missions
from .resume import HubSession
from .records import LinkHealth, State, Stats
from .slots import DEFAULT_MAX_IN_FLIGHT
from .streams import Streams
from .transactions import Transactions

__all__ = ["SessionCore"]

log = logging.getLogger("hubwire")

#: seconds before a failed discovery is tried again
DISCOVERY_RETRY = 1.0
_ANSWERS = frozenset((m.ACK, m.NAK, m.RESPONSE, m.CHUNK))
_NOT_LINKED = bytes((NakCode.NOT_LINKED,))
_DEVICE_TRANSACTIONS = frozenset((m.REQUEST, m.CONTROL))
_ACKS = frozenset((m.ACK, m.NAK))



def measured_ms(since_ms: Optional[int]) -> Optional[int]:
    """A device's measured heartbeat interval, None until measured (its first heartbeat after a start
    carries 0: there was no previous one)."""
    return since_ms or None

class SessionCore:
    """One hub-side session with one device, living on ``loop`` (construct it on that loop)."""

    def __init__(self, transport: Transport, *, dispatch: Any, connect_timeout: float = 5.0,
                 heartbeat_ms: int = 250, retry_timeout: float = 0.1, tries: int = 5, cache_dir: Any = None,
                 progress: Optional[Callable[[int, int], None]] = None, hub: Optional[HubChannels] = None,
                 max_in_flight: int = DEFAULT_MAX_IN_FLIGHT, hub_session: Optional[HubSession] = None,
                 hub_later: bool = False) -> None:
        self.loop = asyncio.get_running_loop()
        self._loop_thread = threading.current_thread()
        self.url = transport.url
        self.connect_timeout = connect_timeout
        self.retry_timeout = retry_timeout
        self.tries = tries
        #: transactions in flight at most; more wait their turn (session/slots.py)
        self.max_in_flight = max_in_flight
        self.progress = progress
        self.dispatch = dispatch
        self.stats = Stats()
        self.state = State.CONNECTING
        self.fatal: Optional[BaseException] = None
        self.descriptor: Optional[Descriptor] = None
        self.descriptor_nonce: Optional[int] = None
        # (device nonce, board id) once asked: the id a device reports is read once per boot
        self.board_id: Optional[Tuple[Optional[int], Optional[str]]] = None
        # (device nonce,) once that boot of the device refused a window read (session/windows.py)
        self.whole_reads_only: Optional[Tuple[Optional[int]]] = None
        self.discovery_error: Optional[BaseException] = None
        self.progress_at = 0.0
        self.link_lost_cbs: List[Callable[[], Any]] = []
        self.link_restored_cbs: List[Callable[[], Any]] = []
        self.reconnect_cbs: List[Callable[[Descriptor], Any]] = []
        #: the hub's own channels for this device (declared beforehand: ``hub_declared``)
        self.hub_declared = hub is not None
        #: the caller declares the hub channels after connecting: open() does not ask for them
        self.hub_later = hub_later
        self.hub = HubSide(self, hub if hub is not None else HubChannels())
        # hub_session: the nonce to say hello with, and what a resumed session left (session/resume.py)
        self.link = Link(transport, self.loop, self.stats, heartbeat_ms, self,
                         hub_session.nonce if hub_session else None)
        self.tx = Transactions(self)
        self.hub.resume(hub_session)
        self.discovery = Discovery(self, DescriptorCache(cache_dir))
        self.events = Events(self)
        self.streams = Streams(self)
        self.missions = Missions(self)
        self._discovering: Optional["asyncio.Task[None]"] = None
        self._discovery_timer: Optional[asyncio.TimerHandle] = None
        self._changed: "asyncio.Future[None]" = self.loop.create_future()
        #: notified with every state change and device hello, for threads waiting on the core
        self.sync_cv = threading.Condition()

    # ------------------------------------------------------------------------------ queries

    @property
    def closed(self) -> bool:
        return self.state is State.CLOSED

    @property
    def device_hello(self) -> Optional[m.Hello]:
        return self.link.device_hello

    def is_ready(self) -> bool:
        return self.state is State.READY

    def decodable(self) -> Optional[Descriptor]:
        """The descriptor if it is the one of the device's current session, else None."""
        h = self.link.device_hello
        if self.descriptor is None or h is None or self.descriptor_nonce != h.nonce:
            return None
        return self.descriptor

    def dispatch_pending(self) -> int:
        return self.dispatch.pending()  # type: ignore[no-any-return]

    def health(self) -> LinkHealth:
        now = time.monotonic()
        link = self.link
        hb = link.peer_hb
        return LinkHealth(
            state=self.state.value,
            last_rx_age=(now - link.last_rx) if link.last_rx else None,
            heartbeat_age=(now - link.peer_hb_at) if link.peer_hb_at is not None else None,
            device_heartbeats=link.peer_hb_count,
            device_heartbeat_ms=link.device_hello.heartbeat_ms if link.device_hello else None,
            hub_counters=link.decoder.counters(),
            device_counters={"crc": hb.crc, "overflow": hb.overflow, "dropped": hb.dropped} if hb else {},
            stats=self.stats.as_dict(),
            measured_heartbeat_ms=measured_ms(hb.since_ms if hb else None),
            hub_heartbeat_ms=link.heartbeat_ms,
            hub_heartbeat_since_ms=link.sent_since_ms or None,
        )

    def hub_descriptor_id(self) -> "tuple[int, int]":
        """FNV-1a hash and length of the hub's own descriptor, for the hub hello (0, 0: none)."""
        raw = self.hub.channels.descriptor()
        return (self.hub.channels.descriptor_hash(), len(raw)) if raw else (0, 0)

    # ---------------------------------------------------------------------------- lifecycle

    def _notify(self) -> None:
        """Wake everything waiting for a state change."""
        fut, self._changed = self._changed, self.loop.create_future()
        fut.set_result(None)
        with self.sync_cv:
            self.sync_cv.notify_all()

    async def _changes(self, timeout: float) -> None:
        await asyncio.wait((self._changed,), timeout=max(0.0, timeout))

    async def changes(self, timeout: float) -> None:
        """Wait up to ``timeout`` s for the next state change or :meth:`wake`."""
        await self._changes(timeout)

    def wake(self) -> None:
        """Wake what waits for a change (from any thread)."""
        if threading.current_thread() is getattr(self, "_loop_thread", None):
            self._notify()
        else:
            self.loop.call_soon_threadsafe(self._notify)

    async def open(self) -> None:
        """Open the transport, handshake and discover (HubwireError, Timeout, ProtocolVersionError,
        DescriptorError); on failure the session is closed."""
        try:
            self.link.open()
        except PortOpenError:
            self.state = State.CLOSED
            raise
        except OSError as e:
            self.state = State.CLOSED
            raise HubwireError(f"cannot open {self.url}: {e}") from e
        try:
            await self._await_connected()
        except BaseException:
            await self.close()
            raise

    async def _await_connected(self) -> None:
        deadline = time.monotonic() + self.connect_timeout
        while self.device_hello is None and self.fatal is None:
            left = deadline - time.monotonic()
            if left <= 0:
                d = self.link.decoder
                raise Timeout(no_answer_message(self.url, self.connect_timeout, d.counters(), d.noise(),
                                                frames=d.frames, hello_ms=round(HELLO_INTERVAL * 1000)))
            await self._changes(left)
        # the handshake is done; discovery may take longer than the deadline as long as it makes
        # progress (a big descriptor on a slow line), but not connect_timeout without any
        self.progress_at = time.monotonic()
        lost: Optional[Tuple[float, LinkLost]] = None  # the first loss during discovery, the last error
        while self.state is not State.READY and self.fatal is None:
            now = time.monotonic()
            idle = now - self.progress_at
            if isinstance(self.discovery_error, LinkLost):
                lost = (lost[0] if lost else now, self.discovery_error)
            # a link lost during discovery is linked again, until a blocked loop() shows or the deadline
            if lost and (now - lost[0] >= self.connect_timeout or self.link.blocked()):
                hint = "" if "loop()" in str(lost[1]) else self.link.blocked_hint()
                raise LinkLost(f"{lost[1]}{hint}")
            if idle >= self.connect_timeout:
                raise Timeout(f"device on {self.url} answered the handshake but its descriptor did not "
                              f"arrive: no progress for {self.connect_timeout:g} s{self.link.blocked_hint()}")
            if self.discovery_error is not None and not isinstance(self.discovery_error, LinkLost):
                raise self.discovery_error  # a lost link is linked again, and discovery starts again
            if self.state is State.CLOSED:
                raise HubwireError("session closed while connecting")
            await self._changes(min(0.5, self.connect_timeout - idle))
        if self.fatal is not None:
            raise self.fatal
        if self.descriptor is not None and not self.hub_later:
            self.hub.check_all(self.descriptor)  # a name the device uses and the hub lacks

    async def close(self) -> None:
        """Cancel streams on the device, fail what waits, close the transport. Idempotent."""
        if self.state is State.CLOSED and self.link.closed:
            return
        if self.state is State.READY:
            for cid in list(self.streams.subs):
                self.streams.send_subscribe(cid, 0, closing=True)
        self.state = State.CLOSED
        self.tx.fail_all(LinkLost("session closed"))
        self.streams.end_all(LinkLost("session closed"))
        for t in (self._discovering, self._discovery_timer):
            if t is not None:
                t.cancel()
        self.hub.close()
        self.link.close()
        self.events.close()
        self.missions.close()
        self._notify()

    def ready_by(self, deadline: float) -> bool:
        """True when READY; LinkLost / HubwireError if lost / closed, Timeout once past ``deadline``
        still connecting; False: not yet (wait for a change)."""
        st = self.state
        if st is State.READY:
            return True
        if st is State.CLOSED:
            raise HubwireError("session is closed")
        if st is State.LOST:
            raise LinkLost(f"link to {self.url} is down")
        if time.monotonic() >= deadline:
            extra = f": {self.discovery_error}" if self.discovery_error else ""
            raise Timeout(f"device on {self.url} is not ready (re-handshaking){extra}")
        return False

    async def check_ready(self, timeout: float) -> None:
        """Return once READY (see :meth:`ready_by`), waiting up to ``timeout`` s while connecting."""
        deadline = time.monotonic() + timeout
        while not self.ready_by(deadline):
            await self._changes(deadline - time.monotonic())

    # ------------------------------------------------------------------------ frames from the link

    def handle(self, f: Frame, now: float) -> None:
        t = f.type
        if t in _DEVICE_TRANSACTIONS or (t == m.CHUNK and len(f.payload) == 3):
            self.hub.answers.on_device_frame(f)  # the device asks the hub (a chunk request has 3 bytes)
        elif t in _ANSWERS:
            if t in _ACKS and self.hub.on_answer(f):
                return
            if self.tx.on_answer(f) and t == m.NAK and f.payload[:1] == _NOT_LINKED:
                # the device lost the link on its side: re-handshake (its hello reply relinks it)
                self.stats.not_linked += 1
                self.link.send_hello(reply=False)
        elif t == m.SAMPLE:
            self.streams.on_sample(f, now)
        elif t == m.EVENT:
            self.events.on_event(f, now)
        elif t == m.MISSION:
            self.missions.on_update(f)
        else:
            # unknown type or a request type the hub never answers: dropped and counted
            self.link.decoder.dropped += 1
            self.stats.unknown_frames += 1

    def on_hello(self, outcome: HelloOutcome) -> None:
        with self.sync_cv:
            self.sync_cv.notify_all()  # threads waiting for a re-link count hellos
        if outcome is HelloOutcome.VERSION:
            if self.fatal is None:
                self.fatal = ProtocolVersionError(self.link.rejected_version, m.PROTOCOL_VERSION)
                self.streams.end_all(self.fatal)
                self._notify()
            return
        if outcome is HelloOutcome.FIRST:
            self._notify()
            self.maybe_discover()
        elif outcome is HelloOutcome.REBOOT:
            self._rebooted()
        elif outcome is HelloOutcome.RESTORED:
            self._restored()
        elif outcome is HelloOutcome.ANNOUNCE and self.state is State.READY:
            # the device declared the link lost on its side (we kept hearing it): it announced
            # itself, we answered, so it is linked again; its failsafes fired meanwhile
            self.stats.rehandshakes += 1
            self._lost_callbacks()
            self.streams.interrupt()  # its subscriptions ended: subscribed again once restored
            self._restored()

    def _lost_callbacks(self) -> None:
        self.stats.link_lost += 1
        for cb in list(self.link_lost_cbs):
            self.dispatch(cb)

    def _rebooted(self) -> None:
        self.stats.reboots += 1
        self.tx.device_rebooted()  # a new device session remembers none of the hub's seqs
        self.events.last_seq = None
        self.hub.link_down()
        self.descriptor_nonce = None  # rediscover (from the cache if the hash is known)
        self.tx.fail_all(LinkLost("device rebooted"))
        self.missions.rebooted()
        self.streams.interrupt()  # subscribed again once rediscovered
        if self.state is State.READY:
            self._lost_callbacks()  # it was up but we had not noticed the reboot: report the loss too
        if self.state is not State.CLOSED:
            self.state = State.CONNECTING
        if self._discovering is not None:
            self._discovering.cancel()
            self._discovering = None
        self._notify()
        self.maybe_discover()

    def _restored(self) -> None:
        h = self.link.device_hello
        self.state = State.READY if h is not None and self.descriptor_nonce == h.nonce else State.CONNECTING
        self.stats.link_restored += 1
        if h is not None:
            self.missions.restored(h.nonce)
        log.info("hubwire: link to %s restored", self.url)
        for cb in list(self.link_restored_cbs):
            self.dispatch(cb)
        self._notify()
        if self.state is State.READY:
            self.streams.resume()
            self.hub.on_ready()
        self.maybe_discover()

    def link_down(self, why: str) -> None:
        """Declare the link lost: fail calls and streams, tell the application, say hello again."""
        was_up = self.state is State.READY or self.link.linked
        self.link.down()
        if self.state is not State.CLOSED:
            self.state = State.LOST if self.device_hello is not None else State.CONNECTING
        exc = LinkLost(f"link to {self.url} lost ({why}){self.link.blocked_hint()}")
        self.tx.fail_all(exc)
        self.hub.link_down()
        self.missions.link_down()  # runs go on on the board; their updates wait for the link
        self.streams.interrupt()  # streams ride through: subscribed again once the link is back
        self._notify()
        if was_up:
            log.info("hubwire: link to %s lost (%s)", self.url, why)
            self._lost_callbacks()

    def hub_nonce_changed(self) -> None:
        self.hub.nonce_changed()

    def port_down(self) -> None:
        if self.link.linked or self.state is State.READY:
            self.link_down("port disappeared")

    # ---------------------------------------------------------------------------- discovery

    def maybe_discover(self) -> None:
        """Start discovery if the device's session has no descriptor yet and none is running."""
        h = self.link.device_hello
        if (h is None or not self.link.linked or self.descriptor_nonce == h.nonce or self._discovering is not None
                or self.state is State.CLOSED):
            return
        if self._discovery_timer is not None:
            self._discovery_timer.cancel()
            self._discovery_timer = None
        self.discovery_error = None
        self._discovering = self.loop.create_task(self._discover(h))

    async def _discover(self, hello: m.Hello) -> None:
        try:
            desc = await self.discovery.load(hello)
        except asyncio.CancelledError:
            return
        except BaseException as e:  # noqa: BLE001 - reported to connect() or logged
            self._discovering = None
            self.discovery_error = e
            if not isinstance(e, LinkLost) and self.state is not State.CLOSED:
                log.warning("hubwire: discovery on %s failed: %s", self.url, e)
            self._discovery_timer = self.loop.call_later(DISCOVERY_RETRY, self.maybe_discover)
            self._notify()
            return
        self._discovering = None
        current = self.link.device_hello
        if current is None or current.nonce != hello.nonce:
            self.maybe_discover()  # rebooted again meanwhile
            return
        first = self.descriptor is None
        self.descriptor = desc
        self.descriptor_nonce = hello.nonce
        if self.link.linked and self.state is not State.CLOSED:
            self.state = State.READY
            self.streams.resume()
            self.hub.on_ready()
        self._notify()
        if not first:
            for cb in list(self.reconnect_cbs):
                self.dispatch(cb, desc)

    def report_progress(self, received: int, total: int) -> None:
        if self.progress is not None:
            self.dispatch(self.progress, received, total)
