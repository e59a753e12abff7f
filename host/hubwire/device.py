"""The user-facing synchronous :class:`Device` and :func:`connect`."""
from __future__ import annotations

from typing import Any, Callable, List, Optional, Tuple, cast

from . import ops, roads
from .board import BoardAPI
from .descriptor import Channel, Descriptor
from .diagnose import ACCESS_WORDS
from .errors import HubwireError, NakError, Timeout
from .hub_face import HubMethods
from .iterators import EventStream, Stream
from .job import Job
from .ports import KNOWN_USB_VIDS, find_port
from .session import LinkHealth, Session
from .session.hub_channels import HubSide
from .text import clip, clip_list, show
from .transport import Transport
from .wire import messages as m

__all__ = ["Device", "Stream", "EventStream", "connect", "find_port", "KNOWN_USB_VIDS", "channel_table"]


def connect(url: Optional[str] = None, baudrate: int = 115200, *, timeout: float = 5.0,
            transport: Optional[Transport] = None, **kwargs: Any) -> "Device":
    """Open ``url`` (anything ``serial.serial_for_url`` accepts; ``None`` finds the board by USB id)
    or ``transport``, ride through the board's reset, handshake, discover its channels and return a
    :class:`Device`.

    ``timeout`` is the connect deadline in seconds. Other keyword arguments go to
    :class:`hubwire.session.Session` (``heartbeat_ms``, ``retry_timeout``, ``tries``, ``cache_dir``,
    ``progress``, ``on_link_lost``, ``on_link_restored``, ``on_reconnect``, ``serial_kwargs``,
    ``max_in_flight``: transactions in flight at once, default 64, the rest wait their turn) and
    ``hub``: a :class:`hubwire.HubChannels` the device may use; a hub channel the device expects
    that it lacks, or declares with another type or access, raises :class:`HubChannelError` here,
    also without ``hub=`` (the error names each one), unless ``hub_later=True``: the program
    declares them on the device once connected (``dev.provide``, ``dev.accept``, ...).

    With ``hubwire serve`` running, a board name (``connect("rover")``), a port the service owns, or
    no URL with one board served reach the board through the service (docs/SERVICE.md).

    Use it as a context manager to close the link at the end::

        with hubwire.connect("/dev/ttyACM0") as rover:
            rover.left = 0.5
    """
    road = roads.service_road()
    if transport is None and road is not None:  # a board name, or a port hubwire serve owns
        remote = road.open_routed(url, timeout, kwargs)
        if remote is not None:
            return cast(Device, remote)  # a RemoteDevice (hubwire.client.remote)
    if url is None and transport is None:
        url = find_port()
    session = Session(url, baudrate, connect_timeout=timeout, transport=transport, **kwargs)
    session.open()
    return Device(session)


def _fmt_num(x: Any) -> str:
    if x is None:
        return ""
    if isinstance(x, float) and x.is_integer():
        return str(int(x))
    return str(x)




def channel_table(desc: Descriptor, hub: bool = False) -> str:
    """The channel table of a descriptor as text (``hub``: of the hub channels the device uses)."""
    rows = [("id", "name", "type", "access", "unit", "range", "failsafe", "description")]
    for c in desc.hub if hub else desc.channels:
        rng = ""
        if c.min is not None or c.max is not None:
            rng = f"{_fmt_num(c.min) or '*'}..{_fmt_num(c.max) or '*'}"
        rows.append((str(c.id), c.name, c.type_name, ",".join(ACCESS_WORDS[a] for a in c.access),
                     c.unit or "", rng, "" if c.failsafe is None else _fmt_num(c.failsafe), c.description or ""))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(v.ljust(w) for v, w in zip(r, widths)).rstrip() for r in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


class Device(HubMethods, BoardAPI):
    """A connected device: its channels as items, and as attributes where the name is free.

    - ``dev["left"]`` / ``dev.left`` reads a readable channel;
    - ``dev["left"] = 0.5`` / ``dev.left = 0.5`` writes (type and range checked before sending,
      ACK awaited, :class:`NakError` on refusal);
    - ``dev.beep(200)`` / ``dev["beep"](200)`` calls a callable channel and returns its result;
    - ``dev.read(name)``, ``dev.write(name, value)``, ``dev.call(name, arg)`` do the same by name;
    - ``dev.on("bumper", callback)``, ``dev.events()``, ``dev.stream("imu", hz=50)``;
    - ``job = dev.start("drive", 2.0)`` starts a mission (:class:`hubwire.Job`: ``feedback()``,
      ``result()``, ``cancel()``);
    - ``print(dev.table())`` shows the table of channels;
    - the other direction: ``dev.provide``, ``dev.accept``, ``dev.action``, ``dev.event`` declare
      hub channels the device may use, ``dev.notify(name, value)`` sends it a hub event.

    It implements :class:`hubwire.board.BoardAPI` on both roads: over a direct session, and through
    ``hubwire serve`` (:class:`hubwire.client.remote.RemoteDevice`).

    Methods and properties of this class always win: a channel called ``close``, ``read``,
    ``session``, ``name`` or ``__class__`` never hides or replaces one. Reach it with ``dev["close"]``
    (``dev.close = 1`` raises AttributeError instead of writing).
    """

    __slots__ = ("_session",)
    _session: Session

    def __init__(self, session: Session) -> None:
        object.__setattr__(self, "_session", session)

    # ---------------------------------------------------------------------- properties

    @property
    def session(self) -> Session:
        """The underlying :class:`hubwire.session.Session`."""
        return self._session

    def _hub_side(self) -> HubSide:
        return self._session.core.hub

    def wait_notified(self, timeout: Optional[float] = 5.0) -> None:
        """Return once every hub event queued with :meth:`notify` was acknowledged by the device
        (before closing, say); :class:`hubwire.Timeout` after ``timeout`` s (None: no limit)."""
        core = self._session.core
        with core.sync_cv:
            if not core.sync_cv.wait_for(lambda: not core.hub.queue or core.closed, timeout):
                raise Timeout(f"{len(core.hub.queue)} hub events still wait for the device after {timeout} s")

    def _desc(self) -> Descriptor:
        d = self._session.descriptor
        if d is None:
            raise HubwireError("device not discovered yet")
        return d

    @property
    def descriptor(self) -> Descriptor:
        """The device's parsed :class:`Descriptor`."""
        return self._desc()

    @property
    def name(self) -> str:
        """Device name from its descriptor (a channel called ``name`` is ``dev["name"]``)."""
        return self._desc().name

    @property
    def firmware(self) -> Optional[str]:
        return self._desc().firmware

    @property
    def channels(self) -> Tuple[Channel, ...]:
        return self._desc().channels

    @property
    def state(self) -> str:
        """``"ready"``, ``"connecting"``, ``"lost"`` or ``"closed"``."""
        return self._session.state.value

    @property
    def url(self) -> str:
        return self._session.url

    def health(self) -> LinkHealth:
        """Link health: heartbeat age, error counters of both sides, state."""
        return self._session.health()

    # ------------------------------------------------------------------------- channels

    def channel(self, name: str) -> Channel:
        """The :class:`Channel` called ``name`` (KeyError listing the channels if there is none)."""
        return ops.channel(self._session.descriptor, name)

    def board_id(self, *, timeout: Optional[float] = None) -> Optional[str]:
        """This board's id in hex (the chip's unique id, or the one its sketch keeps), which tells
        two boards running one sketch apart; None when the board has none. Read once per boot."""
        core = self._session.core
        known = ops.cached_board_id(core)
        if known is not ops.UNASKED:
            return cast(Optional[str], known)
        try:
            a = self._session.transact(m.REQUEST, 0, b"", timeout=timeout, what="board id")
        except NakError as e:
            return ops.remember_board_id(core, None, e)
        return ops.remember_board_id(core, a)

    def read(self, name: str, *, timeout: Optional[float] = None) -> Any:
        """Read a readable channel's current value."""
        ch = ops.readable(self._session.descriptor, name)
        return ch.codec.decode(self._session.request(ch.id, timeout=timeout, what=name))

    def write(self, name: str, value: Any, *, timeout: Optional[float] = None) -> None:
        """Write a writable channel; returns once the device acknowledged it (exactly once)."""
        ch, payload = ops.write_payload(self._session.descriptor, name, value)
        self._session.control(ch.id, payload, timeout=timeout, what=name)

    def call(self, name: str, arg: Any = None, *, timeout: Optional[float] = None) -> Any:
        """Call a callable channel with ``arg`` (None for no argument); return its result."""
        ch, payload = ops.call_payload(self._session.descriptor, name, arg)
        return ops.call_result(ch, self._session.control(ch.id, payload, timeout=timeout, what=name))

    def start(self, name: str, goal: Any = None, *, timeout: Optional[float] = None) -> "Job":
        """Start mission ``name`` with ``goal`` (None for a mission without goal) and return its
        :class:`hubwire.Job` once the board answered with the run number (exactly once, as a write).
        :class:`NakError` ``BUSY`` while a run of that mission runs, ``REJECTED`` when the sketch refused."""
        from .job import start_job

        return start_job(self._session, name, goal, timeout)

    # --------------------------------------------------------------------------- events

    def on(self, name: str, callback: Callable[..., Any]) -> Callable[[], None]:
        """Call ``callback(value)`` for every event of channel ``name`` (``"*"``: every event, with
        the :class:`ReceivedEvent`), on the dispatcher thread. Also ``"link_lost"``,
        ``"link_restored"`` (no argument) and ``"reconnect"`` (the new descriptor). Returns a
        function removing it."""
        s = self._session
        if name in ("link_lost", "link_restored", "reconnect"):
            getattr(s, f"add_{name}")(callback)
            return lambda: s.remove_callback(name, callback)
        key = ops.event_key(s.descriptor, name)
        s.add_event_callback(key, callback)
        return lambda: s.remove_event_callback(key, callback)

    def events(self, *names: str, timeout: Optional[float] = None) -> EventStream:
        """Iterator over incoming events (of ``names``, or all) from now on; see :class:`EventStream`."""
        for n in names:
            self.channel(n)
        return EventStream(self._session, names or None, timeout)

    def stream(self, name: str, hz: Optional[float] = None, *, interval_ms: Optional[int] = None,
               meta: bool = False, timeout: Optional[float] = None, maxlen: int = 1024) -> Stream:
        """Subscribe to a streamable channel at ``hz`` (or ``interval_ms``; default 10 Hz).

        Returns a :class:`Stream`: iterate it for values, use it as a context manager to cancel the
        subscription at the end. ``stream.granted_ms`` is the interval the device granted.
        """
        ch = ops.stream_channel(self._session.descriptor, name)
        interval = ops.interval_for(hz, interval_ms)
        return Stream(self._session, ch, interval, meta=meta, timeout=timeout, maxlen=maxlen)

    # ------------------------------------------------------------------- item / attribute access

    def _bound_call(self, ch: Channel) -> Callable[..., Any]:
        name = ch.name

        def method(arg: Any = None, *, timeout: Optional[float] = None) -> Any:
            return self.call(name, arg, timeout=timeout)
        method.__name__ = name
        method.__doc__ = f"{name}{ch.type_name}" + (f": {ch.description}" if ch.description else "")
        return method

    def __getitem__(self, name: str) -> Any:
        ch = self.channel(name)
        if ch.mission:
            raise ops.not_a_mission(ch)
        return self._bound_call(ch) if ch.callable else self.read(name)

    def __setitem__(self, name: str, value: Any) -> None:
        self.write(name, value)

    def __getattr__(self, name: str) -> Any:
        # only reached when no method or property has this name
        d = self._session.descriptor
        ch = d.by_name(name) if d is not None and not name.startswith("_") else None
        if ch is None:
            if name.startswith("__"):
                raise AttributeError(name)
            raise AttributeError(f"device {show(d.name) + ' ' if d else ''}has no channel {name!r}"
                                 + (f"; channels: {clip_list(c.name for c in d.channels)}" if d else ""))
        if ch.callable:
            return self._bound_call(ch)
        if ch.mission:
            raise AttributeError(str(ops.not_a_mission(ch)))
        if ch.readable:
            return self.read(name)
        if ch.is_event:
            raise AttributeError(f"{name!r} is an event channel: use dev.on({name!r}, callback) or dev.events()")
        raise AttributeError(f"channel {name!r} is write-only")

    def __setattr__(self, name: str, value: Any) -> None:
        if hasattr(type(self), name) or name.startswith("_"):
            raise AttributeError(f"{name!r} is a Device attribute, not a channel: write a channel of this "
                                 f"name with dev[{name!r}] = value")
        d = self._session.descriptor
        if d is not None and d.by_name(name) is not None:
            self.write(name, value)
            return
        raise AttributeError(f"{name!r} is not a channel of {show(d.name) if d else 'this device'}")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"cannot delete {name!r} from a device")

    def __contains__(self, name: str) -> bool:
        d = self._session.descriptor
        return d is not None and d.by_name(name) is not None

    def __dir__(self) -> List[str]:
        d = self._session.descriptor
        return sorted(set(object.__dir__(self)) | ({c.name for c in d.channels} if d else set()))

    # -------------------------------------------------------------------------- display

    def table(self) -> str:
        """The channel table as text (what ``hubwire info`` prints)."""
        return channel_table(self._desc())

    def __repr__(self) -> str:
        s = self._session
        d = s.descriptor
        if d is None:
            return f"<hubwire.Device on {s.url} ({s.state.value})>"
        fw = f" fw {show(d.firmware)}" if d.firmware else ""
        return f"<hubwire.Device {clip(d.name)}{fw} on {s.url} ({s.state.value}), {len(d.channels)} channels>"

    # ------------------------------------------------------------------------ lifecycle

    def close(self) -> None:
        """Cancel streams and close the link."""
        self._session.close()

    def __enter__(self) -> "Device":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
