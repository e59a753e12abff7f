"""A hub session that goes on across a restart of the hub (PROTOCOL.md 4.2, "Resuming a hub
session"): the nonce the hub says hello with, and what the device may remember of it.

A device that did not reboot takes a hello with the hub nonce it last heard as the same hub session
and keeps its duplicate memories (4.1): the last hub control (until a hub ``R``/``J``/``S``) and the
(seq, id) of the last hub event it delivered. A hub that comes back with that nonce therefore

- re-sends the hub event it had in flight with the seq and id it was first sent with (the device
  acknowledges it again if it had delivered it),
- gives no new event the seq of that event or of the last one the device acknowledged, and
- sends no control before the device has answered an ``R``, ``J`` or ``S`` (it does not know which
  control the device remembers: every seq counts as remembered until then).

A device that rebooted meanwhile (a new device nonce) remembers nothing: all of it is new to it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Tuple

__all__ = ["HubSession"]


@dataclass(frozen=True)
class HubSession:
    """``nonce``: the hub nonce to say hello with (instead of a fresh one). ``resumed``: an earlier
    run of the hub used it with this device; then ``acked`` is the seq of the last hub event the
    device acknowledged and ``head`` the (keeper token, seq, id) of the event that was in flight."""

    nonce: int
    resumed: bool = False
    acked: Optional[int] = None
    head: Optional[Tuple[Any, int, int]] = None
