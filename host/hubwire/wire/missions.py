"""The payloads of missions (PROTOCOL.md 11): the hub's start and cancel (``C`` with an op byte),
the device's mission update ``M`` and the ``r`` answering ``R`` on a mission channel."""
from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any, Dict, Optional

from .frame import Frame
from .messages import CONTROL, MISSION, RESPONSE, PayloadError, _need

__all__ = ["MissionOp", "MissionKind", "MissionUpdate", "MissionState", "describe_mission", "start_payload",
           "cancel_payload"]


def start_payload(goal: bytes) -> bytes:
    """The ``C`` payload that starts a run with the encoded ``goal``."""
    return bytes((MissionOp.START,)) + goal


def cancel_payload(run: int) -> bytes:
    """The ``C`` payload that cancels run ``run``."""
    return bytes((MissionOp.CANCEL, run))


class MissionOp(enum.IntEnum):
    """First byte of a hub ``C`` on a mission channel (PROTOCOL.md 11.2)."""

    START = 1
    CANCEL = 2


class MissionKind(enum.IntEnum):
    """Byte 1 of a mission update ``M`` (PROTOCOL.md 11.3)."""

    PROGRESS = 1
    SUCCEEDED = 2
    FAILED = 3
    CANCELLED = 4


@dataclass(frozen=True)
class MissionUpdate:
    """Mission update payload (``M``, device to hub): run number, kind, then the progress value,
    the result value, the failure code (one byte) or nothing (cancelled)."""

    run: int
    kind: int
    data: bytes = b""

    def pack(self) -> bytes:
        return bytes((self.run, self.kind)) + self.data

    @classmethod
    def unpack(cls, payload: bytes) -> "MissionUpdate":
        _need(payload, 2, "mission update", exact=False)
        u = cls(payload[0], payload[1], bytes(payload[2:]))
        if u.kind not in tuple(MissionKind):
            raise PayloadError(f"mission update kind {u.kind} is not 1..4")
        if (u.kind == MissionKind.FAILED and len(u.data) != 1) or (u.kind == MissionKind.CANCELLED and u.data):
            raise PayloadError(f"mission update kind {MissionKind(u.kind).name.lower()} has {len(u.data)} data bytes")
        return u

    @property
    def final(self) -> bool:
        return self.kind != MissionKind.PROGRESS

    @property
    def code(self) -> int:
        """A failed run's error code (0 for the other kinds)."""
        return self.data[0] if self.kind == MissionKind.FAILED else 0


@dataclass(frozen=True)
class MissionState:
    """The ``r`` answering ``R`` on a mission channel: the latest run number and whether it runs."""

    run: int
    running: bool

    def pack(self) -> bytes:
        return bytes((self.run, int(self.running)))

    @classmethod
    def unpack(cls, payload: bytes) -> "MissionState":
        _need(payload, 2, "mission state")
        if payload[1] > 1:
            raise PayloadError(f"mission state {payload[1]} is not 0 or 1")
        return cls(payload[0], bool(payload[1]))


def describe_mission(frame: Frame, kind: str) -> Optional[Dict[str, Any]]:
    """The frames of PROTOCOL.md 11 by ``kind``: ``mission_start`` / ``mission_cancel`` (hub ``C``),
    ``mission_state`` (the ``r`` to ``R``); ``M`` needs no kind."""
    p = frame.payload
    if frame.type == MISSION:
        u = MissionUpdate.unpack(p)
        out: Dict[str, Any] = {"kind": "mission_update", "run": u.run, "update": MissionKind(u.kind).name.lower()}
        if u.kind == MissionKind.FAILED:
            out["code"] = u.code
        elif u.kind != MissionKind.CANCELLED:
            out["value"] = u.data.hex()
        return out
    if frame.type == CONTROL and kind == "mission_start":
        if not p or p[0] != MissionOp.START:
            raise PayloadError("a mission start begins with op 1")
        return {"kind": "mission_start", "goal": bytes(p[1:]).hex()}
    if frame.type == CONTROL and kind == "mission_cancel":
        _need(p, 2, "mission cancel")
        if p[0] != MissionOp.CANCEL:
            raise PayloadError("a mission cancel begins with op 2")
        return {"kind": "mission_cancel", "run": p[1]}
    if frame.type == RESPONSE and kind == "mission_state":
        st = MissionState.unpack(p)
        return {"kind": "mission_state", "run": st.run, "running": st.running}
    return None
