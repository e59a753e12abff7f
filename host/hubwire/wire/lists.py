"""Variable-length arrays on the wire (PROTOCOL.md §6): ``{"t": "i16", "vc": 8}`` is a list of up to
8 ``i16``, sent as one count byte ``n`` then ``n`` elements back to back.

Checks run in the order a device judges them (the order of strings): a count over the capacity is
``BAD_VALUE`` whatever the payload length, then a length other than ``1 + n * size`` is
``BAD_LENGTH``, then the elements in order (a bool not 0/1 ``BAD_VALUE``; the channel's range,
``OUT_OF_RANGE``, is checked by :meth:`hubwire.descriptor.Channel.check`).
"""
from __future__ import annotations

import json
import struct
from typing import Any, List, Mapping

from ..errors import InvalidValue
from .scalars import BAD_LENGTH, BAD_VALUE, INTEGER_TYPES, SCALARS, describe_value, scalar_checker
from .codec import Codec

__all__ = ["ListCodec"]


class ListCodec(Codec):
    """A Python ``list`` of up to ``capacity`` scalars (int, float or bool)."""

    kind = "list"

    def __init__(self, type_obj: Mapping[str, Any], where: str = "value") -> None:
        super().__init__(type_obj)
        t = type_obj["t"]
        self.scalar = t
        self.capacity = int(type_obj["vc"])
        fmt, self.elem_size, _, _ = SCALARS[t]
        self.size = None  # it varies with the count
        self.max_size = 1 + self.capacity * self.elem_size
        self._fmt = fmt
        self._elem = scalar_checker(t, where)
        self._where = where
        self._is_bool = t == "bool"

    def _items(self, value: Any) -> List[Any]:
        ok_bytes = isinstance(value, (bytes, bytearray)) and self.scalar == "u8"
        if not ok_bytes and (isinstance(value, (str, bytes, bytearray, Mapping))
                             or not hasattr(value, "__len__") or not hasattr(value, "__iter__")):
            raise InvalidValue(f"{self._where}: expected a list of up to {self.capacity} {self.scalar}, "
                               f"got {describe_value(value)}", BAD_VALUE)
        if len(value) > self.capacity:
            raise InvalidValue(f"{self._where}: {len(value)} elements exceed the capacity of {self.capacity}",
                               BAD_VALUE)
        return [self._elem(v) for v in value]

    def encode(self, value: Any) -> bytes:
        items = self._items(value)
        return bytes((len(items),)) + struct.pack(f"<{len(items)}{self._fmt}", *items)

    def decode(self, payload: bytes) -> List[Any]:
        if not payload:
            raise InvalidValue(f"{self.name} payload must hold a count byte, got 0 bytes", BAD_LENGTH)
        n = payload[0]
        if n > self.capacity:
            raise InvalidValue(f"list count {n} exceeds the capacity of {self.capacity}", BAD_VALUE)
        want = 1 + n * self.elem_size
        if len(payload) != want:
            raise InvalidValue(f"{self.name} payload with {n} elements must be {want} bytes, got {len(payload)}",
                               BAD_LENGTH)
        items = list(struct.unpack_from(f"<{n}{self._fmt}", payload, 1))
        if self._is_bool:
            for v in items:
                if v > 1:
                    raise InvalidValue(f"bool byte must be 0 or 1, got {v}", BAD_VALUE)
            items = [v == 1 for v in items]
        return items

    def check(self, value: Any) -> List[Any]:
        return self._items(value)

    def from_json(self, obj: Any) -> Any:
        return list(obj) if isinstance(obj, (list, tuple)) else obj

    def to_json(self, value: Any) -> Any:
        return list(value)

    def parse_text(self, text: str) -> List[Any]:
        """A JSON list (``[1, 2, 3]``) or comma-separated elements (``1,2,3``; empty text: no element)."""
        s = text.strip()
        if s.startswith("["):
            try:
                obj = json.loads(s)
            except ValueError:
                raise InvalidValue(f"cannot parse {text!r} as {self.name} (give a JSON list or 1,2,3)",
                                   BAD_VALUE) from None
            return self.check(self.from_json(obj))
        parts = [p.strip() for p in s.split(",")] if s else []
        return self.check([self._parse_one(p) for p in parts])

    def _parse_one(self, s: str) -> Any:
        if self._is_bool:
            low = s.lower()
            if low in ("1", "true", "on", "yes", "0", "false", "off", "no"):
                return low in ("1", "true", "on", "yes")
        try:
            return int(s, 0) if self.scalar in INTEGER_TYPES else float(s)
        except ValueError:
            raise InvalidValue(f"cannot parse {s!r} as {self.scalar} in {self.name}", BAD_VALUE) from None
