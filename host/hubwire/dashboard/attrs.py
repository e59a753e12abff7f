"""Attributes on page elements, set as values and never parsed.

``element.props('k="..."')`` parses its string: a value holding a quote ends the attribute and the
rest becomes new props, and a prop named ``:x`` is evaluated as JavaScript by Vue. A board's name,
ids and channel texts come from the device, so every attribute carrying one is set here, as one
dict entry whose name is ours and whose value is plain text (the browser escapes it).
"""
from __future__ import annotations

from typing import Any, TypeVar

__all__ = ["tag"]

E = TypeVar("E")


def tag(element: E, *flags: str, **data: Any) -> E:
    """Set ``data-hw-<name>`` (underscores become ``-``) to ``str(value)`` for each of ``data``, and
    each of ``flags`` (our own Quasar flags such as ``dense``) to true; returns ``element``."""
    props = element.props  # type: ignore[attr-defined]
    for flag in flags:
        props[flag] = True
    for name, value in data.items():
        props["data-hw-" + name.replace("_", "-")] = str(value)
    return element
