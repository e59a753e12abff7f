"""The user-facing :class:`Device` and :func:`connect`."""
from __future__ import annotations

import queue
import time
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple

from .descriptor import Channel, Descriptor
from .errors import HubwireError, NoDeviceFound, Timeout
from .session import Event, LinkHealth, Session, StreamSample, _Subscription
from .wire import messages as m

__all__ = ["Device", "Stream", "EventStream", "connect", "find_port", "KNOWN_USB_VIDS"]

#: USB vendor ids of boards and USB-serial bridges commonly used with microcontrollers
KNOWN_USB_VIDS: Dict[int, str] = {
    0x2341: "Arduino",
    0x2A03: "Arduino (.org)",
    0x1A86: "CH340",
    0x0403: "FTDI",
    0x10C4: "CP210x",
    0x16C0: "Teensy",
    0x2E8A: "RP2040",
    0x303A: "Espressif",
}


def _port_line(p: Any) -> str:
    ids = f"{p.vid:04x}:{p.pid:04x}" if p.vid is not None else "no USB id"
    desc = p.description if p.description and p.description != "n/a" else ""
    return f"{p.device} ({ids}{', ' + desc if desc else ''})"


def find_port() -> str:
    """Serial port of the one connected board with a known USB vendor id.

    Raises NoDeviceFound naming the ports seen when none or several match.
    """
    from serial.tools import list_ports

    ports = sorted(list_ports.comports(), key=lambda p: p.device)
    matches = [p for p in ports if p.vid in KNOWN_USB_VIDS]
    if len(matches) == 1:
        return matches[0].device
    seen = "; ".join(_port_line(p) for p in ports) or "none"
    if not matches:
        raise NoDeviceFound(
            "no microcontroller board found: no serial port has a known USB id "
            f"({', '.join(f'{v:04x} {n}' for v, n in KNOWN_USB_VIDS.items())}). Ports seen: {seen}. "
            "Pass the port explicitly, e.g. connect('/dev/ttyACM0').")
    raise NoDeviceFound(
        f"{len(matches)} boards found, pass the one to use explicitly: "
        + "; ".join(f"{_port_line(p)} [{KNOWN_USB_VIDS[p.vid]}]" for p in matches))


def connect(url: Optional[str] = None, baudrate: int = 115200, *, timeout: float = 5.0, **kwargs: Any) -> "Device":
    """Open ``url`` (anything ``serial.serial_for_url`` accepts; ``None`` finds the board by USB id),
    ride through the board's reset, handshake, discover its channels and return a :class:`Device`.

    ``timeout`` is the connect deadline in seconds. Other keyword arguments go to
    :class:`hubwire.session.Session` (``heartbeat_ms``, ``retry_timeout``, ``tries``, ``cache_dir``,
    ``progress``, ``on_link_lost``, ``on_link_restored``, ``on_reconnect``).

    Use it as a context manager to close the link at the end::

        with hubwire.connect("/dev/ttyACM0") as rover:
            rover.left = 0.5
    """
    if url is None:
        url = find_port()
    session = Session(url, baudrate, connect_timeout=timeout, **kwargs)
    session.open()
    return Device(session)


def _fmt_num(x: Any) -> str:
    if x is None:
        return ""
    if isinstance(x, float) and x.is_integer():
        return str(int(x))
    return str(x)


ACCESS_WORDS = {"r": "read", "w": "write", "c": "call", "e": "event", "s": "stream"}


class Stream:
    """A subscription to a streamable channel: iterate to get values (or :class:`StreamSample` with
    ``meta=True``). Ends the subscription on :meth:`close` / leaving the ``with`` block.

    Iteration raises :class:`LinkLost` if the link drops (subscriptions end with the link) and
    :class:`Timeout` if no sample arrives within ``timeout`` seconds (when given).
    """

    def __init__(self, session: Session, channel: Channel, interval_ms: int, *, meta: bool = False,
                 timeout: Optional[float] = None, maxlen: int = 1024) -> None:
        self._session = session
        self.channel = channel
        self.meta = meta
        self.timeout = timeout
        self._sub: Optional[_Subscription] = session.open_stream(channel.id, interval_ms, maxlen, what=channel.name)
        #: interval the device granted, ms
        self.granted_ms = self._sub.granted_ms
        #: samples lost (gaps in the device's sample counter)
        self.lost = 0

    def __iter__(self) -> "Stream":
        return self

    def __next__(self) -> Any:
        sub = self._sub
        if sub is None:
            raise StopIteration
        deadline = None if self.timeout is None else time.monotonic() + self.timeout
        with sub.cv:
            while not sub.queue:
                if sub.ended is not None:
                    if isinstance(sub.ended, StopIteration):
                        raise StopIteration
                    raise sub.ended
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    raise Timeout(f"no sample of {self.channel.name} within {self.timeout:g} s")
                sub.cv.wait(left)
            s: StreamSample = sub.queue.popleft()
        self.lost += s.lost
        return s if self.meta else s.value

    def get(self, timeout: Optional[float] = None) -> Optional[Any]:
        """Next sample within ``timeout`` s, or None."""
        old = self.timeout
        self.timeout = timeout
        try:
            return next(self)
        except (Timeout, StopIteration):
            return None
        finally:
            self.timeout = old

    def close(self, wait: bool = True) -> None:
        """End the subscription (cancelled on the device when this was its last consumer)."""
        sub, self._sub = self._sub, None
        if sub is not None:
            try:
                self._session.close_stream(sub, wait=wait)
            except HubwireError:
                pass

    def __enter__(self) -> "Stream":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            if self._sub is not None:
                self.close(wait=False)
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass

    def __repr__(self) -> str:
        return f"<Stream {self.channel.name} every {self.granted_ms} ms{' (closed)' if self._sub is None else ''}>"


class EventStream:
    """Iterator over events (all, or those of the given channel names), from its creation on.

    Yields :class:`hubwire.session.Event` objects (``.name``, ``.value``, ``.seq``, ``.time``).
    ``timeout`` (s) makes iteration stop after that long without an event; :meth:`get` polls.
    """

    def __init__(self, session: Session, names: Optional[Sequence[str]] = None, timeout: Optional[float] = None) -> None:
        self._session = session
        self._names = set(names) if names else None
        self.timeout = timeout
        self._q: Optional["queue.Queue[Event]"] = session.event_queue(self._names)

    def get(self, timeout: Optional[float] = None) -> Optional[Event]:
        """Next event within ``timeout`` seconds (None: wait forever), or None."""
        q = self._q
        if q is None:
            return None
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            try:
                ev = q.get(timeout=left) if left is None or left > 0 else q.get_nowait()
            except queue.Empty:
                return None
            if ev is None:  # session closed
                self.close()
                return None
            if self._names is None or ev.name in self._names:
                return ev

    def __iter__(self) -> Iterator[Event]:
        while self._q is not None:
            ev = self.get(self.timeout)
            if ev is None:
                return
            yield ev

    def close(self) -> None:
        q, self._q = self._q, None
        if q is not None:
            self._session.drop_event_queue(q)

    def __enter__(self) -> "EventStream":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


#: Device methods that a channel of the same name does not hide (reach such channels with dev[name])
_METHODS = frozenset(("read", "write", "call", "on", "events", "stream", "channel", "close", "health", "table"))


class Device:
    """A connected device: its channels as attributes and items.

    - ``dev.left`` / ``dev["left"]`` reads a readable channel;
    - ``dev.left = 0.5`` / ``dev["left"] = 0.5`` writes (type and range checked before sending,
      ACK awaited, :class:`NakError` on refusal);
    - ``dev.beep(200)`` calls a callable channel and returns its result;
    - ``dev.read(name)``, ``dev.write(name, value)``, ``dev.call(name, arg)`` do the same by name
      (use them for channels whose names collide with a method, e.g. ``read``);
    - ``dev.on("bumper", callback)``, ``dev.events()``, ``dev.stream("imu", hz=50)``;
    - ``print(dev)`` shows the table of channels.

    Channel attributes hide the properties below (``dev.name`` is the channel ``name`` if there is
    one; ``dev.descriptor.name`` is always the device name) but not the methods listed in
    ``_METHODS``; ``dev["read"]`` reaches a channel called ``read``.
    """

    def __init__(self, session: Session) -> None:
        object.__setattr__(self, "_session", session)

    # ---------------------------------------------------------------------- properties

    @property
    def session(self) -> Session:
        """The underlying :class:`hubwire.session.Session`."""
        return self._session  # type: ignore[no-any-return]

    def _desc(self) -> Descriptor:
        d = self._session.descriptor
        if d is None:
            raise HubwireError("device not discovered yet")
        return d  # type: ignore[no-any-return]

    @property
    def descriptor(self) -> Descriptor:
        """The device's parsed :class:`Descriptor`."""
        return self._desc()

    @property
    def name(self) -> str:
        """Device name from its descriptor."""
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
        return self._session.state.value  # type: ignore[no-any-return]

    @property
    def url(self) -> str:
        return self._session.url  # type: ignore[no-any-return]

    def health(self) -> LinkHealth:
        """Link health: heartbeat age, error counters of both sides, state."""
        return self._session.health()  # type: ignore[no-any-return]

    # ------------------------------------------------------------------------- channels

    def channel(self, name: str) -> Channel:
        """The :class:`Channel` called ``name`` (KeyError listing the channels if there is none)."""
        ch = self._desc().by_name(name)
        if ch is None:
            raise KeyError(f"{self._desc().name} has no channel {name!r}; channels: "
                           f"{', '.join(c.name for c in self._desc().channels)}")
        return ch

    def read(self, name: str, *, timeout: Optional[float] = None) -> Any:
        """Read a readable channel's current value."""
        ch = self.channel(name)
        if not ch.readable:
            raise HubwireError(f"channel {name!r} is not readable (access {ch.access!r})")
        payload = self._session.request(ch.id, timeout=timeout, what=name)
        return ch.codec.decode(payload)

    def write(self, name: str, value: Any, *, timeout: Optional[float] = None) -> None:
        """Write a writable channel; returns once the device acknowledged it (exactly once)."""
        ch = self.channel(name)
        if not ch.writable:
            raise HubwireError(f"channel {name!r} is not writable (access {ch.access!r})")
        payload = ch.codec.encode(ch.check(value))
        self._session.control(ch.id, payload, timeout=timeout, what=name)

    def call(self, name: str, arg: Any = None, *, timeout: Optional[float] = None) -> Any:
        """Call a callable channel with ``arg`` (None for no argument); return its result."""
        ch = self.channel(name)
        if not ch.callable:
            raise HubwireError(f"channel {name!r} is not callable (access {ch.access!r})")
        if ch.codec.kind == "void":
            if arg is not None:
                raise HubwireError(f"{name}() takes no argument")
            payload = b""
        else:
            if arg is None:
                raise HubwireError(f"{name}() needs an argument of type {ch.codec.name}")
            payload = ch.codec.encode(ch.check(arg))
        a = self._session.control(ch.id, payload, timeout=timeout, what=name)
        if a.type == m.ACK:
            return None
        assert ch.returns is not None
        return ch.returns.decode(a.payload)

    # --------------------------------------------------------------------------- events

    def on(self, name: str, callback: Callable[[Any], Any]) -> Callable[[], None]:
        """Call ``callback(value)`` for every event of channel ``name`` (``"*"``: every event, with
        the :class:`Event`), on the dispatcher thread. Also ``"link_lost"``, ``"link_restored"``
        (no argument) and ``"reconnect"`` (the new descriptor). Returns a function removing it."""
        s = self._session
        if name == "link_lost":
            s.add_link_lost(callback)
            return lambda: s._link_lost_cbs.remove(callback)
        if name == "link_restored":
            s.add_link_restored(callback)
            return lambda: s._link_restored_cbs.remove(callback)
        if name == "reconnect":
            s.add_reconnect(callback)
            return lambda: s._reconnect_cbs.remove(callback)
        key: Optional[str] = None
        if name != "*":
            ch = self.channel(name)
            if not ch.is_event:
                raise HubwireError(f"channel {name!r} is not an event (access {ch.access!r})")
            key = name
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
        ch = self.channel(name)
        if not ch.streamable:
            raise HubwireError(f"channel {name!r} is not streamable (access {ch.access!r})")
        if interval_ms is None:
            interval_ms = 100 if hz is None else max(1, int(round(1000.0 / hz)))
        if not 1 <= interval_ms <= 0xFFFF:
            raise ValueError("interval must be 1..65535 ms")
        return Stream(self._session, ch, interval_ms, meta=meta, timeout=timeout, maxlen=maxlen)

    # ------------------------------------------------------------------- attribute access

    def _channel_attr(self, ch: Channel) -> Any:
        name = ch.name
        if ch.callable:
            def method(arg: Any = None, *, timeout: Optional[float] = None) -> Any:
                return self.call(name, arg, timeout=timeout)
            method.__name__ = name
            method.__doc__ = f"{name}{ch.type_name}" + (f": {ch.description}" if ch.description else "")
            return method
        if ch.readable:
            return self.read(name)
        if ch.is_event:
            raise AttributeError(f"{name!r} is an event channel: use dev.on({name!r}, callback) or dev.events()")
        raise AttributeError(f"channel {name!r} is write-only")

    def __getattribute__(self, name: str) -> Any:
        # channels win over properties (a channel may be called "name" or "state"), not over methods
        if name[:1] != "_" and name not in _METHODS:
            d = object.__getattribute__(self, "_session").descriptor
            if d is not None:
                ch = d.by_name(name)
                if ch is not None:
                    return object.__getattribute__(self, "_channel_attr")(ch)
        return object.__getattribute__(self, name)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        d = self._session.descriptor
        raise AttributeError(f"device {d.name + ' ' if d else ''}has no channel {name!r}"
                             + (f"; channels: {', '.join(c.name for c in d.channels)}" if d else ""))

    def __setattr__(self, name: str, value: Any) -> None:
        if name.startswith("_"):
            object.__setattr__(self, name, value)
            return
        d = self._session.descriptor
        if d is not None and d.by_name(name) is not None:
            self.write(name, value)
            return
        raise AttributeError(f"{name!r} is not a channel of {d.name if d else 'this device'}")

    def __getitem__(self, name: str) -> Any:
        ch = self.channel(name)
        if ch.callable:
            return self._channel_attr(ch)
        return self.read(name)

    def __setitem__(self, name: str, value: Any) -> None:
        self.write(name, value)

    def __contains__(self, name: str) -> bool:
        d = self._session.descriptor
        return d is not None and d.by_name(name) is not None

    def __dir__(self) -> List[str]:
        d = self._session.descriptor
        return sorted(set(super().__dir__()) | ({c.name for c in d.channels} if d else set()))

    # -------------------------------------------------------------------------- display

    def table(self) -> str:
        """The channel table as text (what ``print(dev)`` shows)."""
        rows = [("id", "name", "type", "access", "unit", "range", "failsafe", "description")]
        for c in self._desc().channels:
            rng = ""
            if c.min is not None or c.max is not None:
                rng = f"{_fmt_num(c.min) or '*'}..{_fmt_num(c.max) or '*'}"
            rows.append((str(c.id), c.name, c.type_name, ",".join(ACCESS_WORDS[a] for a in c.access),
                         c.unit or "", rng, "" if c.failsafe is None else _fmt_num(c.failsafe), c.description or ""))
        widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
        lines = ["  ".join(v.ljust(w) for v, w in zip(r, widths)).rstrip() for r in rows]
        lines.insert(1, "  ".join("-" * w for w in widths))
        return "\n".join(lines)

    def __repr__(self) -> str:
        d = self._session.descriptor
        if d is None:
            return f"<hubwire.Device on {self._session.url} ({self._session.state.value})>"
        head = f"<hubwire.Device {d.name!r}{' fw ' + d.firmware if d.firmware else ''} on {self._session.url} ({self._session.state.value})>"
        return head + "\n" + self.table()

    # ------------------------------------------------------------------------ lifecycle

    def close(self) -> None:
        """Cancel streams and close the link."""
        self._session.close()

    def __enter__(self) -> "Device":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
