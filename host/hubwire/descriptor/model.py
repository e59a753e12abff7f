"""Parse and validate a device descriptor (PROTOCOL.md §7, docs/descriptor.schema.json).

:func:`parse_descriptor` accepts the raw descriptor bytes and returns a :class:`Descriptor` whose
:class:`Channel` objects carry ready-made value codecs. Every defect raises
:class:`hubwire.errors.DescriptorError` with a message naming the offending place, e.g.
``ch[3] ("imu").f[1]: unknown type 'i17'``.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any, Dict, Optional, Tuple

from ..errors import InvalidValue
from ..wire.values import Codec

__all__ = ["MAX_DESCRIPTOR_SIZE", "MAX_DEPTH", "MAX_VALUE", "Channel", "Descriptor"]

#: largest descriptor the hub accepts, bytes
MAX_DESCRIPTOR_SIZE = 16 * 1024
#: deepest JSON nesting the format has: object > ch array > channel object > f array > field object
MAX_DEPTH = 5

NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
NAME_MAX = 32
ACCESS_LETTERS = "rwcesm"
TOP_KEYS = {"p", "n", "fw", "ch", "hub"}
CHANNEL_KEYS = {"id", "n", "a", "t", "c", "vc", "f", "rt", "rc", "rvc", "pt", "pc", "pmax", "u", "min", "max", "fs", "d"}
#: largest value (payload) a descriptor may declare: a fragment's u16 total (PROTOCOL.md 12)
MAX_VALUE = 0xFFFF
#: largest capacity of a variable-length array: its count is one byte
MAX_LIST = 255
FIELD_KEYS = {"n", "t", "c"}


@dataclass(frozen=True)
class Channel:
    """One channel of a device, as its descriptor declares it.

    ``codec`` encodes/decodes the channel's value (the argument, for a callable); ``returns`` is the
    codec of a callable's return value (``None`` for other channels). A mission (access ``m``) has
    its goal in ``codec``, its result in ``returns``, its progress in ``progress`` and the progress
    value at completion, when declared, in ``progress_max``.
    """

    id: int
    name: str
    access: str
    codec: Codec
    type: Dict[str, Any]
    unit: Optional[str] = None
    min: Optional[float] = None
    max: Optional[float] = None
    failsafe: Any = None
    description: Optional[str] = None
    returns: Optional[Codec] = None
    progress: Optional[Codec] = None
    progress_max: Optional[float] = None

    @property
    def readable(self) -> bool:
        return "r" in self.access

    @property
    def writable(self) -> bool:
        return "w" in self.access

    @property
    def callable(self) -> bool:
        return "c" in self.access

    @property
    def is_event(self) -> bool:
        return "e" in self.access

    @property
    def streamable(self) -> bool:
        return "s" in self.access

    @property
    def mission(self) -> bool:
        return "m" in self.access

    @property
    def type_name(self) -> str:
        """Readable type, e.g. ``f32``, ``i16[3]``, ``str[16]``; for callables ``(arg) -> ret``."""
        if self.callable or self.mission:
            arg = "" if self.codec.kind == "void" else self.codec.name
            ret = self.returns.name if self.returns is not None else "void"
            if self.mission:
                prog = self.progress.name if self.progress is not None else "void"
                return f"({arg}) -> {ret}, progress {prog}"
            return f"({arg}) -> {ret}"
        return self.codec.name

    @property
    def range(self) -> Optional[Tuple[Optional[float], Optional[float]]]:
        if self.min is None and self.max is None:
            return None
        return (self.min, self.max)

    def check(self, value: Any) -> Any:
        """Normalise ``value`` for this channel: type check, then the declared ``min``..``max``.

        Raises :class:`hubwire.errors.InvalidValue` (code ``OUT_OF_RANGE`` for a range violation).
        """
        v = self.codec.check(value)
        if self.min is not None or self.max is not None:
            from ..wire.messages import NakCode

            items = v if isinstance(v, (tuple, list)) else (v,)
            for x in items:
                if (x != x  # NaN: never inside a declared range
                        or (self.min is not None and x < self.min) or (self.max is not None and x > self.max)):
                    raise InvalidValue(
                        f"{self.name}: {x} is outside the declared range {_fmt(self.min)}..{_fmt(self.max)}",
                        NakCode.OUT_OF_RANGE)
        return v


def _fmt(x: Optional[float]) -> str:
    if x is None:
        return "*"
    return str(int(x)) if float(x).is_integer() else repr(x)


@dataclass(frozen=True)
class Descriptor:
    """A parsed descriptor: device ``name``, ``firmware`` and its ``channels`` (in declaration order).

    ``hub`` lists the hub channels the device uses (key ``"hub"``), their ``id`` being the hub id
    (1..N in order) and their access the device's own: ``r`` it reads, ``w`` writes, ``c`` calls,
    ``e`` receives events."""

    protocol: int
    name: str
    firmware: Optional[str]
    channels: Tuple[Channel, ...]
    raw: bytes = field(repr=False)
    hash: int = 0
    hub: Tuple[Channel, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "_by_id", {c.id: c for c in self.channels})
        object.__setattr__(self, "_by_name", {c.name: c for c in self.channels})

    def by_id(self, id: int) -> Optional[Channel]:
        """Channel with this id, or None."""
        found: Optional[Channel] = self._by_id.get(id)  # type: ignore[attr-defined]
        return found

    def by_name(self, name: str) -> Optional[Channel]:
        """Channel with this name, or None."""
        found: Optional[Channel] = self._by_name.get(name)  # type: ignore[attr-defined]
        return found

    def __iter__(self):  # type: ignore[no-untyped-def]
        return iter(self.channels)

    def __len__(self) -> int:
        return len(self.channels)

