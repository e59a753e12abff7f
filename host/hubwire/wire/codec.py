"""The base of every value codec (:func:`hubwire.wire.values.codec_for` builds them): what a codec
of any type offers, and the readable name of a type. Its own module, so that the codecs of
:mod:`.values` and :mod:`.lists` both build on it and :mod:`.values` can build a list's codec."""
from __future__ import annotations

import json
from typing import Any, Mapping, Optional

from ..errors import InvalidValue
from .scalars import BAD_VALUE

__all__ = ["Codec", "type_name"]


def type_name(obj: Mapping[str, Any]) -> str:
    """Human-readable name of a type object: ``f32``, ``u16[3]``, ``str[16]``, ``struct{ax: f32}``."""
    t = obj.get("t")
    if t == "struct":
        return "struct{" + ", ".join(f"{f['n']}: {type_name(f)}" for f in obj.get("f", ())) + "}"
    if "c" in obj:
        return f"{t}[{obj['c']}]"
    if "vc" in obj:
        return f"{t}[<={obj['vc']}]"
    return str(t)


class Codec:
    """Encoder/decoder for one type; build with :func:`codec_for`.

    Attributes: ``name`` (readable type name), ``kind`` (``scalar``, ``array``, ``list``, ``struct``,
    ``str``, ``void``), ``scalar`` (element type name, or None), ``size`` (payload size, None for strings:
    their size varies), ``type_obj`` (the descriptor type object).
    """

    kind = ""

    def __init__(self, type_obj: Mapping[str, Any]) -> None:
        self.type_obj = dict(type_obj)
        self.name = type_name(type_obj)
        self.scalar: Optional[str] = None
        self.size: Optional[int] = 0
        self.max_size = 0

    # subclasses override
    def encode(self, value: Any) -> bytes:
        """Encode ``value`` to payload bytes; raise InvalidValue if it does not fit the type."""
        raise NotImplementedError

    def decode(self, payload: bytes) -> Any:
        """Decode payload bytes; raise InvalidValue(BAD_LENGTH / BAD_VALUE) if malformed."""
        raise NotImplementedError

    def check(self, value: Any) -> Any:
        """Normalise ``value`` (lists become tuples, dicts become structs) or raise InvalidValue."""
        return self.decode(self.encode(value)) if self.kind != "scalar" else self._check(value)  # type: ignore[attr-defined]

    def from_json(self, obj: Any) -> Any:
        """Python value from its JSON form (lists for arrays, objects for structs)."""
        return obj

    def to_json(self, value: Any) -> Any:
        """JSON form of a decoded value."""
        return value

    def parse_text(self, text: str) -> Any:
        """Parse a command-line argument into a value of this type."""
        try:
            return self.from_json(json.loads(text))
        except ValueError:
            raise InvalidValue(f"cannot parse {text!r} as {self.name} (give JSON)", BAD_VALUE) from None

    def __repr__(self) -> str:
        return f"<Codec {self.name}>"
