"""Struct values: tuples with named fields, their classes built at runtime from a descriptor."""
from __future__ import annotations

from operator import itemgetter
from typing import Any, Dict, Sequence, Tuple

__all__ = ["StructValue", "make_struct_class"]


class StructValue(Tuple[Any, ...]):
    """Base of the struct value classes built at runtime: a tuple with named fields.

    ``value.ax``, ``value[0]``, ``value._asdict()``, ``value._replace(ax=1.0)``; fields whose name is a
    Python keyword are reached with ``getattr(value, "from")`` or ``value["from"]``.
    """

    __slots__ = ()
    _fields: Tuple[str, ...] = ()

    def __new__(cls, *args: Any, **kwargs: Any) -> "StructValue":
        if kwargs:
            values = list(args) + [None] * (len(cls._fields) - len(args))
            for k, v in kwargs.items():
                if k not in cls._fields:
                    raise TypeError(f"{cls.__name__} has no field {k!r}")
                values[cls._fields.index(k)] = v
            args = tuple(values)
        if len(args) != len(cls._fields):
            raise TypeError(f"{cls.__name__} takes {len(cls._fields)} values ({', '.join(cls._fields)}), got {len(args)}")
        return tuple.__new__(cls, args)

    def __getitem__(self, key: Any) -> Any:
        if isinstance(key, str):
            try:
                return tuple.__getitem__(self, self._fields.index(key))
            except ValueError:
                raise KeyError(key) from None
        return tuple.__getitem__(self, key)

    def _asdict(self) -> Dict[str, Any]:
        return dict(zip(self._fields, self))

    def _replace(self, **kwargs: Any) -> "StructValue":
        d = self._asdict()
        for k in kwargs:
            if k not in d:
                raise TypeError(f"{type(self).__name__} has no field {k!r}")
        d.update(kwargs)
        return tuple.__new__(type(self), tuple(d[f] for f in self._fields))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(f'{k}={v!r}' for k, v in zip(self._fields, self))})"

    def __getnewargs__(self) -> Tuple[Any, ...]:
        return tuple(self)


def make_struct_class(name: str, fields: Sequence[str]) -> type:
    """Build a :class:`StructValue` subclass called ``name`` with the given field names."""
    ns: Dict[str, Any] = {"__slots__": (), "_fields": tuple(fields)}
    for i, f in enumerate(fields):
        if f not in ns and not f.startswith("__"):
            ns[f] = property(itemgetter(i), doc=f"field {f}")
    return type(name, (StructValue,), ns)
