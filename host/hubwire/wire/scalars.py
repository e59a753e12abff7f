"""Scalar types on the wire (PROTOCOL.md §6): sizes, ranges, and the checks that turn a Python value
into one a scalar of that type can carry (or raise :class:`hubwire.errors.InvalidValue`)."""
from __future__ import annotations

import math
import struct
from typing import Any, Callable, Dict, Optional, Tuple

from ..errors import InvalidValue
from .messages import NakCode

__all__ = ["SCALARS", "INTEGER_TYPES", "FLOAT_TYPES", "NUMERIC_TYPES", "scalar_checker", "describe_value"]

BAD_LENGTH = NakCode.BAD_LENGTH
BAD_VALUE = NakCode.BAD_VALUE
OUT_OF_RANGE = NakCode.OUT_OF_RANGE

F32_MAX = 3.4028234663852886e38

# name -> (struct format char, size, lo, hi) ; lo/hi None for floats and bool
SCALARS: Dict[str, Tuple[str, int, Optional[int], Optional[int]]] = {
    "bool": ("B", 1, 0, 1),
    "u8": ("B", 1, 0, 0xFF),
    "u16": ("H", 2, 0, 0xFFFF),
    "u32": ("I", 4, 0, 0xFFFFFFFF),
    "i8": ("b", 1, -0x80, 0x7F),
    "i16": ("h", 2, -0x8000, 0x7FFF),
    "i32": ("i", 4, -0x80000000, 0x7FFFFFFF),
    "f32": ("f", 4, None, None),
    "f64": ("d", 8, None, None),
}
INTEGER_TYPES = frozenset(("u8", "u16", "u32", "i8", "i16", "i32"))
FLOAT_TYPES = frozenset(("f32", "f64"))
NUMERIC_TYPES = INTEGER_TYPES | FLOAT_TYPES


def describe_value(value: Any) -> str:
    r = repr(value)
    if len(r) > 40:
        r = r[:37] + "..."
    return f"{r} ({type(value).__name__})"


def scalar_checker(t: str, where: str) -> Callable[[Any], Any]:
    """Return a function normalising one Python value for scalar type ``t`` or raising InvalidValue."""
    if t == "bool":
        def check_bool(v: Any) -> bool:
            if v is True or v is False:
                return v
            if isinstance(v, int) and v in (0, 1):
                return bool(v)
            raise InvalidValue(f"{where}: expected a bool, got {describe_value(v)}", BAD_VALUE)
        return check_bool
    if t in INTEGER_TYPES:
        lo, hi = SCALARS[t][2], SCALARS[t][3]

        def check_int(v: Any) -> int:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                if hasattr(v, "__index__") and not isinstance(v, bool):
                    v = v.__index__()
                else:
                    raise InvalidValue(f"{where}: expected an integer for {t}, got {describe_value(v)}", BAD_VALUE)
            if isinstance(v, float):
                if not v.is_integer():
                    raise InvalidValue(f"{where}: expected an integer for {t}, got {describe_value(v)}", BAD_VALUE)
                v = int(v)
            if not lo <= v <= hi:
                raise InvalidValue(f"{where}: {v} is outside the {t} range {lo}..{hi}", OUT_OF_RANGE)
            return int(v)
        return check_int
    if t in FLOAT_TYPES:
        is32 = t == "f32"

        def check_float(v: Any) -> float:
            if isinstance(v, bool):  # True is an int in Python, but not a number for a speed
                raise InvalidValue(f"{where}: expected a number for {t}, got {describe_value(v)}", BAD_VALUE)
            if not isinstance(v, (int, float)):
                try:
                    v = float(v.__float__())  # numpy scalars, Decimal, Fraction
                except (AttributeError, TypeError, ValueError, OverflowError):
                    raise InvalidValue(f"{where}: expected a number for {t}, got {describe_value(v)}", BAD_VALUE) from None
            try:
                f = float(v)
            except OverflowError:
                raise InvalidValue(f"{where}: {v} is too large for {t}", OUT_OF_RANGE) from None
            if is32 and math.isfinite(f) and abs(f) > F32_MAX:
                # values that round to FLT_MAX are fine, anything beyond overflows f32
                try:
                    struct.pack("<f", f)
                except OverflowError:
                    raise InvalidValue(f"{where}: {v} is too large for f32", OUT_OF_RANGE) from None
            return f
        return check_float
    raise ValueError(f"unknown scalar type {t!r}")
