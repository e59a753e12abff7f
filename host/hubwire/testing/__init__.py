"""Helpers for testing hubs and devices: transport wrappers that pause, filter and count
(:mod:`.transports`), the fault-injecting link (:mod:`.faultlink`), and where the repository's
device emulator is."""
from __future__ import annotations

import os
from typing import Any, Optional

from ..transport import SerialTransport
from .transports import TapTransport, WrappingTransport

__all__ = ["TapTransport", "WrappingTransport", "tapped", "tap_of", "repo_root", "emulator_binary"]


def tapped(url: str, baudrate: int = 115200, **serial_kwargs: Any) -> TapTransport:
    """A :class:`TapTransport` around the serial transport of ``url``: ``connect(transport=tapped(url))``."""
    return TapTransport(SerialTransport(url, baudrate, **serial_kwargs))


def tap_of(dev: Any) -> TapTransport:
    """The :class:`TapTransport` a device (or session) was connected through."""
    t: Any = getattr(getattr(dev, "session", dev), "transport")
    while not isinstance(t, TapTransport):
        if not isinstance(t, WrappingTransport):
            raise TypeError(f"{dev!r} was not connected through a TapTransport (use transport=tapped(url))")
        t = t.inner
    return t


def repo_root() -> Optional[str]:
    """The Hubwire source tree this package was installed from (editable install), or None."""
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.abspath(os.path.join(here, "..", "..", ".."))
    return root if os.path.isfile(os.path.join(root, "library.properties")) else None


def emulator_binary() -> str:
    """``$HUBWIRE_EMULATOR``, else the emulator ``make emulator`` builds in the source tree."""
    env = os.environ.get("HUBWIRE_EMULATOR")
    if env:
        return env
    return os.path.join(repo_root() or os.getcwd(), "build", "emulator", "hubwire-emulator")
