"""Hub channels: what the hub offers a device (the other direction of PROTOCOL.md, section 10).

A device may read values the hub provides, write values the hub accepts, call the hub's actions and
receive the hub's events. Declare them once, on a :class:`HubChannels` given to
``connect(..., hub=...)`` (a name the device expects and the hub lacks then raises at connect time),
or on a connected device (``dev.provide(...)``: a type that differs from what the device expects
raises at once)::

    hub = hubwire.HubChannels()
    setpoint = hub.provide("setpoint", 21.5, type="f32", unit="C")   # setpoint.value = 22.0 later
    hub.provide("clock", time.time, type="u32")                      # called on each device read

    @hub.accept("report", type="struct", fields={"temp": "f32", "heater": "bool"})
    def report(value): print(value.temp)                             # return False to refuse

    @hub.action("dock")
    def dock(speed: float) -> bool: return True                      # types from the annotations

    hub.event("mode", type="u8")
    with hubwire.connect(port, hub=hub) as dev:
        dev.notify("mode", 2)                                        # exactly once, in order

Types are written as on the device: ``"f32"``, ``"i16[3]"`` (fixed array), ``"str[16]"`` (bounded
string), ``"struct"`` with ``fields``, or a Python type (``float`` is ``f32``, ``int`` ``i32``,
``bool``, ``None`` void). A channel typed by ``int`` takes the integer type the connected device
declares for it (``u8``, ``u16``...; :meth:`HubChannels.fit`). An action handler returning False
refuses the call (NAK REJECTED) unless the action returns ``bool``. The hub describes itself with the same JSON as a device
(:meth:`HubChannels.descriptor`), so every declaration is checked by the descriptor parser.
"""
from __future__ import annotations

import inspect
import json
import re
import threading
import typing
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional, Union

from .descriptor import Channel
from .descriptor.parse import parse_descriptor
from .errors import DescriptorError, HubChannelError
from .wire.messages import NakCode, fnv1a32

__all__ = ["HubChannels", "HubChannel", "TypeSpec", "bind_status"]

TypeSpec = Union[str, type, None, Mapping[str, Any]]
_PY_TYPES: Dict[Any, str] = {float: "f32", int: "i32", bool: "bool", type(None): "void"}
_ARRAY = re.compile(r"\s*(\w+)\s*\[\s*(\d+)\s*\]\s*\Z")


def _type_obj(spec: TypeSpec, fields: Any = None, where: str = "") -> Dict[str, Any]:
    """A descriptor type object (``{"t": ..., "c": ..., "f": ...}``) from a type spec."""
    if isinstance(spec, Mapping):
        return dict(spec)
    if spec is None or isinstance(spec, type):
        if spec not in _PY_TYPES:
            raise HubChannelError(f"{where}: no wire type for {spec!r}; give type=\"f32\", \"i16[3]\", \"str[16]\"...")
        return {"t": _PY_TYPES[spec]}
    if not isinstance(spec, str):
        raise HubChannelError(f"{where}: type must be a string like 'f32' or a Python type, got {spec!r}")
    if spec == "struct":
        if not fields:
            raise HubChannelError(f"{where}: type 'struct' needs fields={{'name': 'f32', ...}}")
        items = fields.items() if isinstance(fields, Mapping) else fields
        return {"t": "struct", "f": [{"n": n, **_type_obj(t, where=f"{where}.{n}")} for n, t in items]}
    mt = _ARRAY.match(spec)
    return {"t": mt.group(1), "c": int(mt.group(2))} if mt else {"t": spec.strip()}


def _hint(fn: Callable[..., Any], key: Optional[str]) -> Any:
    if key is None:
        return inspect_missing
    try:
        return typing.get_type_hints(fn).get(key, inspect_missing)
    except Exception:  # noqa: BLE001 - unresolvable annotations: explicit types are needed
        return inspect_missing


#: no usable annotation
inspect_missing = object()


class HubChannel:
    """One declared hub channel. ``value`` is what a device reads (a variable-like channel) or the
    last value a device wrote; ``channel`` is the parsed descriptor entry (codec, range)."""

    def __init__(self, entry: Dict[str, Any], *, source: Any = None,
                 getter: Optional[Callable[[], Any]] = None, on_write: Optional[Callable[[Any], Any]] = None,
                 fn: Optional[Callable[..., Any]] = None) -> None:
        self.entry = entry
        self.getter = getter
        self.on_write = on_write
        self.fn = fn
        self.channel: Channel = _check_entry(entry)
        self._value = None if source is None else self.channel.check(source)
        self.name = self.channel.name
        self.access = self.channel.access
        # what the device may do with it, as the parsed entry says
        self.readable, self.writable = self.channel.readable, self.channel.writable
        self.callable, self.is_event = self.channel.callable, self.channel.is_event
        #: (argument or value, return value) typed by a Python ``int``: the device's integer type fits
        self.loose_int = (False, False)

    @property
    def value(self) -> Any:
        """The current value: the getter's result for a function-backed channel."""
        return self.getter() if self.getter is not None else self._value

    @value.setter
    def value(self, v: Any) -> None:
        if self.getter is not None:
            raise HubChannelError(f"hub channel {self.name!r} reads a function; it has no value to set")
        self._value = self.channel.check(v)

    def store(self, v: Any) -> None:
        """A device wrote ``v`` (already checked)."""
        if self.getter is None:
            self._value = v

    def __call__(self, fn: Callable[[Any], Any]) -> Callable[[Any], Any]:
        """As a decorator (``@hub.accept("x", type="f32")``): ``fn`` handles the device's writes."""
        self.on_write = fn
        return fn

    def __repr__(self) -> str:
        return f"<HubChannel {self.name} {self.access} {self.channel.type_name}>"


def _check_entry(entry: Dict[str, Any]) -> Channel:
    """The entry checked by the descriptor parser (as a device would see it in the hub's descriptor)."""
    doc = json.dumps({"p": 1, "n": "hub", "ch": [dict(entry, id=1)]}, separators=(",", ":"))
    try:
        return parse_descriptor(doc).channels[0]
    except DescriptorError as e:
        why = re.sub(r"^descriptor ch\[0\]( \([^)]*\))?:? ?", "", str(e))
        raise HubChannelError(f"hub channel {entry.get('n')!r}: {why}") from None


def bind_status(expected: Channel, hc: Optional[HubChannel]) -> int:
    """Status of a device's hub channel ``expected`` against the hub's ``hc`` (0 bound, else the NAK
    code of the bind report): UNKNOWN_CHANNEL, NOT_WRITABLE, NOT_READABLE, BAD_LENGTH (types differ)."""
    a = expected.access
    if hc is None or ("e" in a and not hc.is_event):
        return NakCode.UNKNOWN_CHANNEL
    if ("w" in a and not hc.writable) or ("c" in a and not hc.callable):
        return NakCode.NOT_WRITABLE
    if "r" in a and not hc.readable:
        return NakCode.NOT_READABLE
    return 0 if _same(expected, hc) else NakCode.BAD_LENGTH


def _same(expected: Channel, hc: HubChannel) -> bool:
    """The same wire types (argument and return value for an action)."""
    mine = hc.channel
    ret = (expected.returns and expected.returns.type_obj) == (mine.returns and mine.returns.type_obj)
    return expected.codec.type_obj == mine.codec.type_obj and ("c" not in expected.access or ret)


class HubChannels:
    """The hub's own channels, offered to the devices it is connected to (see the module docs).

    One object may serve several devices. Listeners (the sessions using it) are told of every
    change and may refuse a declaration (a type the connected device does not expect)."""

    def __init__(self, name: str = "hub") -> None:
        self.name = name
        self._channels: Dict[str, HubChannel] = {}
        self._ids: Dict[str, int] = {}
        self._next_id = 1
        self._lock = threading.RLock()
        self._listeners: List[Any] = []
        self._raw = b""

    # ------------------------------------------------------------------------- declaring

    def provide(self, name: str, source: Any, *, type: TypeSpec = None, fields: Any = None, unit: Optional[str] = None,
                min: Optional[float] = None, max: Optional[float] = None, doc: Optional[str] = None,
                writable: bool = False, on_write: Optional[Callable[[Any], Any]] = None) -> HubChannel:
        """A value the device may read: ``source`` is the value (change it later with
        ``channel.value = ...``) or a function called on each read. ``writable=True`` (or an
        ``on_write``) lets the device write it too. Without ``type`` it comes from the value
        (``float`` is f32, ``int`` i32, ``bool``) or the function's return annotation."""
        getter = source if callable(source) else None
        if type is None:
            type = _hint(source, "return") if getter is not None else builtins_type(source)
            if type is inspect_missing:
                raise HubChannelError(f"hub channel {name!r}: give type= (the function has no return annotation)")
        access = "rw" if writable or on_write is not None else "r"
        entry = self._entry(name, access, _type_obj(type, fields, name), unit, min, max, doc)
        return self._add(_loose(HubChannel(entry, source=None if getter else source, getter=getter,
                                           on_write=on_write), type is int))

    def accept(self, name: str, on_write: Optional[Callable[[Any], Any]] = None, *, type: TypeSpec = None,
               fields: Any = None, unit: Optional[str] = None, min: Optional[float] = None,
               max: Optional[float] = None, doc: Optional[str] = None, initial: Any = None) -> Any:
        """A value the device may write (type, ``min``..``max`` checked before ``on_write(value)``
        runs; ``on_write`` returning False or raising refuses it with NAK REJECTED). Without
        ``on_write`` it works as a decorator. The last value written is ``channel.value``."""
        def declare(cb: Optional[Callable[[Any], Any]]) -> HubChannel:
            spec = type if type is not None else (_hint(cb, _first_param(cb)) if cb is not None else None)
            if spec is None or spec is inspect_missing:
                raise HubChannelError(f"hub channel {name!r}: give type= (or annotate the handler's parameter)")
            entry = self._entry(name, "w", _type_obj(spec, fields, name), unit, min, max, doc)
            return self._add(_loose(HubChannel(entry, source=initial, on_write=cb), spec is int))
        if on_write is None and type is None:
            return _Decorator(declare)  # the type comes from the handler's annotation
        return declare(on_write)

    def action(self, name: str, fn: Optional[Callable[..., Any]] = None, *, type: TypeSpec = None,
               returns: TypeSpec = None, doc: Optional[str] = None) -> Any:
        """An action the device may call with one argument and a return value; the argument and
        return types come from ``type=`` / ``returns=`` or from ``fn``'s annotations (no parameter:
        no argument; ``-> None`` or no return annotation: nothing returned); ``fn`` returning False
        refuses the call (NAK REJECTED) unless the action returns ``bool``. Decorator or direct."""
        def declare(f: Callable[..., Any]) -> HubChannel:
            param = _first_param(f)
            arg = type if type is not None else (_hint(f, param) if param else "void")
            if arg is inspect_missing:
                raise HubChannelError(f"hub action {name!r}: annotate parameter {param!r} or give type=")
            ret = returns if returns is not None else _hint(f, "return")
            t = _type_obj(arg, where=name)
            entry = self._entry(name, "c", t, None, None, None, doc or None)
            rt = {"t": "void"} if ret is inspect_missing or ret is None else _type_obj(ret, where=name + " return")
            if rt["t"] != "void":
                entry["rt"] = rt["t"]
                if "c" in rt:
                    entry["rc"] = rt["c"]
            return self._add(_loose(HubChannel(entry, fn=f), arg is int, ret is int))
        return declare if fn is None else declare(fn)

    def event(self, name: str, *, type: TypeSpec, fields: Any = None, unit: Optional[str] = None,
              doc: Optional[str] = None) -> HubChannel:
        """An event the hub sends to the device with ``dev.notify(name, value)``."""
        hc = HubChannel(self._entry(name, "e", _type_obj(type, fields, name), unit, None, None, doc))
        return self._add(_loose(hc, type is int))

    def remove(self, name: str) -> None:
        """Withdraw a channel (its hub-side id is not reused)."""
        with self._lock:
            hc = self._channels.pop(name)
            self._changed(hc, removed=True)

    # --------------------------------------------------------------------------- helpers

    def _entry(self, name: str, access: str, t: Dict[str, Any], unit: Optional[str], lo: Optional[float],
               hi: Optional[float], doc: Optional[str]) -> Dict[str, Any]:
        e: Dict[str, Any] = {"id": 0, "n": name, "a": access, **t}
        for k, v in (("u", unit), ("min", lo), ("max", hi), ("d", doc)):
            if v is not None:
                e[k] = v
        return e

    def fit(self, expected: Channel) -> None:
        """Give a channel declared with a Python ``int`` the integer type the device declares for
        it (``u8``, ``u16``...), so ``int`` needs no ``type=``; anything else stays as declared."""
        with self._lock:
            hc = self._channels.get(expected.name)
            fitted = None if hc is None else _fitted(hc, expected)
            if fitted is not None:
                fitted.entry["id"] = hc.entry["id"]  # type: ignore[union-attr]
                self._channels[expected.name] = fitted
                self._rebuild()

    def _add(self, hc: HubChannel) -> HubChannel:
        with self._lock:
            for listener in list(self._listeners):  # a connected device says which integer type
                exp = listener.expected(hc.name) if hasattr(listener, "expected") else None
                hc = (_fitted(hc, exp) if exp is not None else None) or hc
            old = self._channels.get(hc.name)
            hc.entry["id"] = self._ids.get(hc.name) or self._new_id()
            self._channels[hc.name] = hc
            try:
                self._changed(hc)
            except BaseException:
                if old is None:
                    del self._channels[hc.name]
                else:
                    self._channels[hc.name] = old
                self._rebuild()
                raise
            self._ids[hc.name] = hc.entry["id"]
        return hc

    def _new_id(self) -> int:
        if self._next_id > 255:
            raise HubChannelError("a hub has at most 255 channels")
        self._next_id += 1
        return self._next_id - 1

    def _changed(self, hc: HubChannel, removed: bool = False) -> None:
        self._rebuild()
        for listener in list(self._listeners):
            listener.hub_changed(hc, removed)

    def _rebuild(self) -> None:
        chs = [hc.entry for hc in self._channels.values()]
        self._raw = b"" if not chs else json.dumps({"p": 1, "n": self.name, "ch": chs},
                                                   separators=(",", ":")).encode()

    def add_listener(self, listener: Any) -> None:
        """``listener.hub_changed(channel, removed)`` on every change; raising refuses a declaration."""
        self._listeners.append(listener)

    def remove_listener(self, listener: Any) -> None:
        if listener in self._listeners:
            self._listeners.remove(listener)

    # --------------------------------------------------------------------------- queries

    def descriptor(self) -> bytes:
        """The hub's descriptor JSON (device descriptor schema; empty when nothing is declared)."""
        return self._raw

    def descriptor_hash(self) -> int:
        """FNV-1a of :meth:`descriptor`, 0 when nothing is declared (as the hub hello carries it)."""
        return fnv1a32(self._raw) if self._raw else 0

    def get(self, name: str) -> Optional[HubChannel]:
        return self._channels.get(name)

    def __getitem__(self, name: str) -> HubChannel:
        try:
            return self._channels[name]
        except KeyError:
            raise KeyError(f"no hub channel {name!r} (hub channels: {', '.join(self._channels) or 'none'})") from None

    def __contains__(self, name: object) -> bool:
        return name in self._channels

    def __iter__(self) -> Iterator[HubChannel]:
        return iter(list(self._channels.values()))

    def __len__(self) -> int:
        return len(self._channels)


_INTEGERS = frozenset({"u8", "i8", "u16", "i16", "u32", "i32", "u64", "i64"})


def _loose(hc: HubChannel, value: bool, returns: bool = False) -> HubChannel:
    hc.loose_int = (value, returns)
    return hc


def _fitted(hc: HubChannel, exp: Channel) -> Optional[HubChannel]:
    """``hc`` with the device's integer types where it was typed by ``int``, or None (no change)."""
    entry = dict(hc.entry)
    t, rt = exp.codec.type_obj, exp.returns.type_obj if exp.returns is not None else None
    if hc.loose_int[0] and set(t) == {"t"} and t["t"] in _INTEGERS and entry.get("c") is None:
        entry["t"] = t["t"]
    if hc.loose_int[1] and rt is not None and set(rt) == {"t"} and rt["t"] in _INTEGERS:
        entry["rt"] = rt["t"]
    if entry == hc.entry:
        return None
    try:
        new = HubChannel(entry, source=None if hc.getter else hc.value, getter=hc.getter, on_write=hc.on_write,
                         fn=hc.fn)
    except (HubChannelError, ValueError):
        return None  # e.g. a value out of the device's range: the mismatch is reported as it is
    return _loose(new, *hc.loose_int)


class _Decorator:
    def __init__(self, declare: Callable[[Any], HubChannel]) -> None:
        self._declare = declare

    def __call__(self, fn: Callable[[Any], Any]) -> Callable[[Any], Any]:
        self._declare(fn)
        return fn


def _first_param(fn: Any) -> Optional[str]:
    try:
        params = list(inspect.signature(fn).parameters.values())
    except (TypeError, ValueError):
        return None
    return params[0].name if params else None


def builtins_type(value: Any) -> TypeSpec:
    """The wire type a plain Python value implies (bool, int → i32, float → f32)."""
    for t in (bool, int, float):
        if isinstance(value, t):
            return t
    raise HubChannelError(f"give type= for a value of type {type(value).__name__}")
