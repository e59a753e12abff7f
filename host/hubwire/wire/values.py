"""Typed values on the wire (PROTOCOL.md §6), built at runtime from a descriptor type object.

A *type object* is the part of a descriptor that names a type: ``{"t": "f32"}``,
``{"t": "u16", "c": 3}`` (fixed array), ``{"t": "str", "c": 16}`` (bounded string),
``{"t": "struct", "f": [{"n": "ax", "t": "f32"}, {"n": "gyro", "t": "i16", "c": 3}]}`` or
``{"t": "void"}``. :func:`codec_for` turns it into a :class:`Codec` that encodes Python values to
payload bytes and decodes payloads back:

- scalars: ``bool``, ``int`` (u8..u32, i8..i32) and ``float`` (f32, f64);
- fixed arrays: tuples; variable-length arrays (``{"t": "u8", "vc": 8}``, :mod:`.lists`): lists;
- structs: instances of a tuple subclass built at runtime with one attribute per field;
- bounded strings: ``str``; void: ``None``.

Encoding errors and decoding errors raise :class:`hubwire.errors.InvalidValue` whose ``code`` is the
NAK code a device would answer (``BAD_LENGTH``, ``BAD_VALUE``, ``OUT_OF_RANGE``).
"""
from __future__ import annotations

import json
import struct
from typing import Any, Callable, List, Mapping, Optional, Sequence, Tuple

from ..errors import InvalidValue

__all__ = ["SCALARS", "Codec", "StructValue", "codec_for", "type_name", "make_struct_class"]

from .scalars import (BAD_LENGTH, BAD_VALUE, FLOAT_TYPES, INTEGER_TYPES, NUMERIC_TYPES, OUT_OF_RANGE,  # noqa: F401
                      SCALARS, describe_value, scalar_checker)
from .structs import StructValue, make_struct_class  # noqa: F401
from .codec import Codec, type_name
from .lists import ListCodec


def _bad_length(name: str, want: Any, got: int) -> InvalidValue:
    return InvalidValue(f"{name} payload must be {want} bytes, got {got}", BAD_LENGTH)


class ScalarCodec(Codec):
    kind = "scalar"

    def __init__(self, type_obj: Mapping[str, Any], where: str = "value") -> None:
        super().__init__(type_obj)
        t = type_obj["t"]
        fmt, size, _, _ = SCALARS[t]
        self.scalar = t
        self.size = self.max_size = size
        self._s = struct.Struct("<" + fmt)
        self._check = scalar_checker(t, where)
        self._is_bool = t == "bool"

    def encode(self, value: Any) -> bytes:
        return self._s.pack(self._check(value))

    def decode(self, payload: bytes) -> Any:
        if len(payload) != self.size:
            raise _bad_length(self.name, self.size, len(payload))
        v = self._s.unpack(payload)[0]
        if self._is_bool:
            if v > 1:
                raise InvalidValue(f"bool byte must be 0 or 1, got {v}", BAD_VALUE)
            return v == 1
        return v

    def parse_text(self, text: str) -> Any:
        s = text.strip()
        if self._is_bool:
            low = s.lower()
            if low in ("1", "true", "on", "yes"):
                return True
            if low in ("0", "false", "off", "no"):
                return False
            raise InvalidValue(f"cannot parse {text!r} as bool (true/false/1/0/on/off)", BAD_VALUE)
        try:
            v: Any = int(s, 0) if self.scalar in INTEGER_TYPES else float(s)
        except ValueError:
            raise InvalidValue(f"cannot parse {text!r} as {self.name}", BAD_VALUE) from None
        return self._check(v)


class _Flat(Codec):
    """Shared machinery of arrays and structs: one precompiled struct of scalars."""

    def _setup(self, layout: List[Tuple[str, str, Optional[int]]], where: str) -> None:
        # layout: (field name, scalar type, count or None)
        fmt = "<"
        self._checks: List[Tuple[int, Optional[int], Callable[[Any], Any]]] = []
        self._bool_slots: List[int] = []
        pos = 0
        size = 0
        for fname, t, count in layout:
            f, s, _, _ = SCALARS[t]
            n = 1 if count is None else count
            fmt += f"{n}{f}"
            size += s * n
            label = where if not fname else f"{where}.{fname}"
            self._checks.append((pos, count, scalar_checker(t, label)))
            if t == "bool":
                self._bool_slots.extend(range(pos, pos + n))
            pos += n
        self._s = struct.Struct(fmt)
        self.size = self.max_size = size
        self._nvalues = pos

    def _decode_flat(self, payload: bytes) -> Tuple[Any, ...]:
        if len(payload) != self.size:
            raise _bad_length(self.name, self.size, len(payload))
        vals = self._s.unpack(payload)
        if self._bool_slots:
            lst = list(vals)
            for i in self._bool_slots:
                if lst[i] > 1:
                    raise InvalidValue(f"bool byte must be 0 or 1, got {lst[i]}", BAD_VALUE)
                lst[i] = lst[i] == 1
            vals = tuple(lst)
        return vals


class ArrayCodec(_Flat):
    kind = "array"

    def __init__(self, type_obj: Mapping[str, Any], where: str = "value") -> None:
        super().__init__(type_obj)
        self.scalar = type_obj["t"]
        self.count = int(type_obj["c"])
        self._setup([("", self.scalar, self.count)], where)
        self._elem = self._checks[0][2]
        self._where = where

    def _check_seq(self, value: Any) -> List[Any]:
        if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__") or not hasattr(value, "__iter__"):
            if isinstance(value, (bytes, bytearray)) and self.scalar == "u8":
                pass
            else:
                raise InvalidValue(f"{self._where}: expected a sequence of {self.count} {self.scalar}, got {describe_value(value)}", BAD_VALUE)
        if len(value) != self.count:
            raise InvalidValue(f"{self._where}: expected {self.count} elements for {self.name}, got {len(value)}", BAD_LENGTH)
        return [self._elem(v) for v in value]

    def encode(self, value: Any) -> bytes:
        return self._s.pack(*self._check_seq(value))

    def decode(self, payload: bytes) -> Tuple[Any, ...]:
        return self._decode_flat(payload)

    def check(self, value: Any) -> Tuple[Any, ...]:
        return tuple(self._check_seq(value))

    def from_json(self, obj: Any) -> Any:
        return tuple(obj) if isinstance(obj, list) else obj

    def to_json(self, value: Any) -> Any:
        return list(value)


class StructCodec(_Flat):
    kind = "struct"

    def __init__(self, type_obj: Mapping[str, Any], where: str = "value", class_name: str = "Struct") -> None:
        super().__init__(type_obj)
        fields = type_obj["f"]
        self.fields = [f["n"] for f in fields]
        self.field_codecs = [codec_for(f, where=f"{where}.{f['n']}") for f in fields]
        self.value_class = make_struct_class(class_name, self.fields)
        self._setup([(f["n"], f["t"], f.get("c")) for f in fields], where)
        self._where = where

    def _flatten(self, value: Any) -> List[Any]:
        if isinstance(value, Mapping):
            missing = [f for f in self.fields if f not in value]
            extra = [k for k in value if k not in self.fields]
            if missing or extra:
                raise InvalidValue(
                    f"{self._where}: struct fields are {', '.join(self.fields)}"
                    + (f"; missing {', '.join(missing)}" if missing else "")
                    + (f"; unknown {', '.join(map(str, extra))}" if extra else ""), BAD_VALUE)
            items = [value[f] for f in self.fields]
        elif isinstance(value, (tuple, list)):
            if len(value) != len(self.fields):
                raise InvalidValue(f"{self._where}: expected {len(self.fields)} fields ({', '.join(self.fields)}), got {len(value)}", BAD_LENGTH)
            items = list(value)
        else:
            raise InvalidValue(f"{self._where}: expected a struct (dict or tuple of {', '.join(self.fields)}), got {describe_value(value)}", BAD_VALUE)
        flat: List[Any] = []
        for (pos, count, chk), item, fc in zip(self._checks, items, self.field_codecs):
            if count is None:
                flat.append(chk(item))
            else:
                flat.extend(fc._check_seq(item))  # type: ignore[attr-defined]
        return flat

    def encode(self, value: Any) -> bytes:
        return self._s.pack(*self._flatten(value))

    def _build(self, vals: Sequence[Any]) -> StructValue:
        out = []
        for pos, count, _ in self._checks:
            out.append(vals[pos] if count is None else tuple(vals[pos:pos + count]))
        return tuple.__new__(self.value_class, out)

    def decode(self, payload: bytes) -> StructValue:
        return self._build(self._decode_flat(payload))

    def check(self, value: Any) -> StructValue:
        return self._build(self._flatten(value))

    def from_json(self, obj: Any) -> Any:
        if isinstance(obj, Mapping):
            return self.check(obj)
        return obj

    def to_json(self, value: Any) -> Any:
        return {f: (list(v) if isinstance(v, tuple) else v) for f, v in zip(self.fields, value)}


class StrCodec(Codec):
    kind = "str"

    def __init__(self, type_obj: Mapping[str, Any], where: str = "value") -> None:
        super().__init__(type_obj)
        self.capacity = int(type_obj["c"])
        self.size = None
        self.max_size = 1 + self.capacity
        self._where = where

    def encode(self, value: Any) -> bytes:
        if isinstance(value, str):
            data = value.encode("utf-8")
        elif isinstance(value, (bytes, bytearray)):
            data = bytes(value)
        else:
            raise InvalidValue(f"{self._where}: expected a string, got {describe_value(value)}", BAD_VALUE)
        if len(data) > self.capacity:
            raise InvalidValue(f"{self._where}: string of {len(data)} UTF-8 bytes exceeds the capacity of {self.capacity}", BAD_VALUE)
        return bytes((len(data),)) + data

    def decode(self, payload: bytes) -> str:
        if not payload:
            raise InvalidValue(f"{self.name} payload must hold a length byte, got 0 bytes", BAD_LENGTH)
        n = payload[0]
        if n > self.capacity:
            raise InvalidValue(f"string length {n} exceeds the capacity of {self.capacity}", BAD_VALUE)
        if len(payload) != 1 + n:
            raise _bad_length(self.name, 1 + n, len(payload))
        return bytes(payload[1:]).decode("utf-8", "replace")

    def check(self, value: Any) -> str:
        self.encode(value)
        return value if isinstance(value, str) else bytes(value).decode("utf-8", "replace")

    def parse_text(self, text: str) -> str:
        """The text itself, or the decoded string if it is a JSON string literal (``'"a b"'``)."""
        if len(text) >= 2 and text[0] == text[-1] == '"':
            try:
                v = json.loads(text)
            except ValueError:
                v = None
            if isinstance(v, str):
                text = v
        return self.check(text)


class VoidCodec(Codec):
    kind = "void"

    def encode(self, value: Any = None) -> bytes:
        if value is not None:
            raise InvalidValue(f"this takes no value, got {describe_value(value)}", BAD_VALUE)
        return b""

    def decode(self, payload: bytes) -> None:
        if payload:
            raise _bad_length("void", 0, len(payload))
        return None

    def check(self, value: Any) -> None:
        self.encode(value)

    def parse_text(self, text: str) -> None:
        raise InvalidValue("this takes no value", BAD_VALUE)


def codec_for(type_obj: Mapping[str, Any], where: str = "value", class_name: str = "Struct") -> Codec:
    """Build the codec of a descriptor type object (assumed valid; see :mod:`hubwire.descriptor`).

    ``where`` names the value in error messages (e.g. the channel name); ``class_name`` names the
    struct value class.
    """
    t = type_obj.get("t")
    if t == "void":
        return VoidCodec(type_obj)
    if t == "str":
        return StrCodec(type_obj, where)
    if t == "struct":
        return StructCodec(type_obj, where, class_name)
    if t in SCALARS:
        if "vc" in type_obj:
            return ListCodec(type_obj, where)
        if "c" in type_obj:
            return ArrayCodec(type_obj, where)
        return ScalarCodec(type_obj, where)
    raise ValueError(f"unknown type {t!r}")
