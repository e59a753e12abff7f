"""Frames of missions (issue 22, docs/PROTOCOL.md 11): test/vectors/missions/frames.json.

Written by generate.py (which imports this module). The hub's start and cancel (`C` on a mission
channel with an op byte first), the device's answers, `R` on a mission channel and its `r`
[run, state], the device's mission updates `M` and the hub's ACKs. Each frame carries a `direction`
(`"hub"`: the hub sends it; `"device"`: the device does) besides the fields of frames.json.

`message` kinds are those of frames.json plus `mission_start` (`goal`: hex), `mission_cancel`
(`run`), `mission_state` (`run`, `running`) and `mission_update` (`run`, `update`: progress,
succeeded, failed or cancelled; `value` in hex for progress and succeeded, `code` for failed).

`scenarios` chain frames by name, in order, for a device that booted with `descriptor`: what a
device answers to each hub frame (and how many starts its sketch sees), and what the hub acks.
"""
from __future__ import annotations

import struct
from typing import Any, Dict, List, Optional

from hubwire.wire.frame import FrameDecoder, encode_frame
from hubwire.wire import messages as m
from hubwire.wire.missions import MissionKind, MissionState, MissionUpdate, cancel_payload, start_payload

# drive: goal f32 metres 0..10, progress f32, result f32; home: no goal, void progress and result
DESCRIPTOR = (b'{"p":1,"n":"rover","ch":[{"id":7,"n":"drive","a":"m","t":"f32","rt":"f32","pt":"f32",'
              b'"u":"m","min":0,"max":10,"pmax":2,"d":"drive straight"},{"id":8,"n":"home","a":"m","t":"void"}]}')
DRIVE, HOME = 7, 8


def f32(x: float) -> bytes:
    return struct.pack("<f", x)


def nak(code: int) -> Dict[str, Any]:
    return {"kind": "nak", "code": code, "error": m.nak_name(code)}


def gen() -> Dict[str, Any]:
    vectors: List[Dict[str, Any]] = []

    def add(name: str, direction: str, t: int, seq: int, cid: int, payload: bytes, message: Dict[str, Any],
            kind: Optional[str] = None) -> None:
        wire = encode_frame(t, seq, cid, payload)
        frames = FrameDecoder(255).feed(wire)
        assert len(frames) == 1 and frames[0] == (t, seq, cid, payload), name
        got = m.describe(frames[0], kind or message.get("kind"))
        assert got == message, (name, got, message)
        vectors.append({"name": name, "direction": direction, "type": t, "seq": seq, "id": cid,
                        "payload": payload.hex(), "wire": wire.hex(), "message": message})

    def start(name: str, seq: int, cid: int, goal: bytes) -> None:
        add(name, "hub", m.CONTROL, seq, cid, start_payload(goal), {"kind": "mission_start", "goal": goal.hex()})

    def answer(name: str, seq: int, cid: int, value: int) -> None:
        add(name, "device", m.RESPONSE, seq, cid, bytes((value,)), {"kind": "response", "value": f"{value:02x}"})

    def refuse(name: str, seq: int, cid: int, code: int) -> None:
        add(name, "device", m.NAK, seq, cid, bytes((code,)), nak(code))

    def update(name: str, seq: int, cid: int, u: MissionUpdate) -> None:
        msg: Dict[str, Any] = {"kind": "mission_update", "run": u.run, "update": MissionKind(u.kind).name.lower()}
        if u.kind == MissionKind.FAILED:
            msg["code"] = u.code
        elif u.kind != MissionKind.CANCELLED:
            msg["value"] = u.data.hex()
        add(name, "device", m.MISSION, seq, cid, u.pack(), msg)
        add(f"hub acknowledges: {name}", "hub", m.ACK, seq, cid, b"", {"kind": "ack"})

    # Start: C [01, goal]; the device answers r [run].
    start("hub starts drive: goal f32 2.0", 0x30, DRIVE, f32(2.0))
    answer("device accepts the start: run 1", 0x30, DRIVE, 1)
    start("hub starts drive while run 1 runs: goal f32 1.0", 0x31, DRIVE, f32(1.0))
    refuse("device refuses the start: BUSY", 0x31, DRIVE, m.NakCode.BUSY)
    start("hub starts drive with a goal out of range: f32 20.0", 0x32, DRIVE, f32(20.0))
    refuse("device refuses the start: OUT_OF_RANGE", 0x32, DRIVE, m.NakCode.OUT_OF_RANGE)
    start("hub starts drive with a goal of the wrong length (2 bytes)", 0x33, DRIVE, b"\x00\x40")
    refuse("device refuses the start: BAD_LENGTH", 0x33, DRIVE, m.NakCode.BAD_LENGTH)
    start("hub starts drive: goal f32 3.0 (the sketch refuses it)", 0x34, DRIVE, f32(3.0))
    refuse("device refuses the start: REJECTED (the start function returned false)", 0x34, DRIVE, m.NakCode.REJECTED)
    start("hub starts home (no goal)", 0x35, HOME, b"")
    answer("device accepts the start of home: run 1", 0x35, HOME, 1)
    start("hub starts drive again: goal f32 1.5", 0x36, DRIVE, f32(1.5))
    answer("device accepts the start: run 2", 0x36, DRIVE, 2)

    # Bad ops and lengths.
    add("hub sends op 3 (unknown)", "hub", m.CONTROL, 0x40, DRIVE, b"\x03", {"kind": "control", "value": "03"})
    refuse("device refuses an unknown op: BAD_VALUE", 0x40, DRIVE, m.NakCode.BAD_VALUE)
    add("hub sends an empty C to a mission", "hub", m.CONTROL, 0x41, DRIVE, b"", {"kind": "control", "value": ""})
    refuse("device refuses an empty C: BAD_LENGTH", 0x41, DRIVE, m.NakCode.BAD_LENGTH)
    add("hub sends a cancel of 3 bytes", "hub", m.CONTROL, 0x42, DRIVE, b"\x02\x01\x00",
        {"kind": "control", "value": "020100"})
    refuse("device refuses a cancel of 3 bytes: BAD_LENGTH", 0x42, DRIVE, m.NakCode.BAD_LENGTH)

    # Cancel: C [02, run]; r [1] it was running (cancel function called), r [0] it was not.
    add("hub cancels drive run 1", "hub", m.CONTROL, 0x43, DRIVE, cancel_payload(1),
        {"kind": "mission_cancel", "run": 1})
    answer("device: run 1 was running, its cancel function was called", 0x43, DRIVE, 1)
    add("hub cancels drive run 1 again", "hub", m.CONTROL, 0x44, DRIVE, cancel_payload(1),
        {"kind": "mission_cancel", "run": 1})
    answer("device: run 1 is not running", 0x44, DRIVE, 0)

    # R on a mission channel: r [latest run, 1 running / 0 not].
    add("hub reads drive's state", "hub", m.REQUEST, 0x45, DRIVE, b"", {"kind": "request", "value": ""})
    add("device: run 1 running", "device", m.RESPONSE, 0x45, DRIVE, MissionState(1, True).pack(),
        {"kind": "mission_state", "run": 1, "running": True})
    add("hub reads drive's state again", "hub", m.REQUEST, 0x46, DRIVE, b"", {"kind": "request", "value": ""})
    add("device: run 1 not running", "device", m.RESPONSE, 0x46, DRIVE, MissionState(1, False).pack(),
        {"kind": "mission_state", "run": 1, "running": False})
    add("hub reads home's state (no run since boot)", "hub", m.REQUEST, 0x47, HOME, b"", {"kind": "request", "value": ""})
    add("device: no run since boot", "device", m.RESPONSE, 0x47, HOME, MissionState(0, False).pack(),
        {"kind": "mission_state", "run": 0, "running": False})

    # M: seq from the device's transaction counter; the hub acks each with its seq and id.
    update("drive run 1 progress f32 0.5", 0x10, DRIVE, MissionUpdate(1, MissionKind.PROGRESS, f32(0.5)))
    update("drive run 1 progress f32 1.25", 0x11, DRIVE, MissionUpdate(1, MissionKind.PROGRESS, f32(1.25)))
    update("drive run 1 succeeded: f32 2.0", 0x12, DRIVE, MissionUpdate(1, MissionKind.SUCCEEDED, f32(2.0)))
    update("drive run 2 failed: code 3", 0x13, DRIVE, MissionUpdate(2, MissionKind.FAILED, b"\x03"))
    update("drive run 1 cancelled", 0x14, DRIVE, MissionUpdate(1, MissionKind.CANCELLED))
    update("home run 1 progress (void)", 0x15, HOME, MissionUpdate(1, MissionKind.PROGRESS))
    update("home run 1 succeeded (void result)", 0x16, HOME, MissionUpdate(1, MissionKind.SUCCEEDED))
    update("drive run 9 progress f32 0.5 (a run the hub does not know)", 0x17, DRIVE,
           MissionUpdate(9, MissionKind.PROGRESS, f32(0.5)))

    s = scenarios()
    names = {v["name"] for v in vectors}
    for sc in s:
        assert all(step in names for step in sc["steps"]), sc["name"]
    return {"description": "Frames of missions (docs/PROTOCOL.md 11): start and cancel (hub C with an op "
                           "byte), R on a mission channel, mission updates M and their ACKs; `direction` is "
                           "who sends the frame; `scenarios` chain them for a device booted with `descriptor`.",
            "descriptor": DESCRIPTOR.decode(),
            "vectors": vectors,
            "scenarios": s}


def scenarios() -> List[Dict[str, Any]]:
    start = "hub starts drive: goal f32 2.0"
    run1 = "device accepts the start: run 1"
    return [
        {"name": "start, then the same start again (a retry): the same run, the sketch started once",
         "steps": [start, run1, start, run1], "sketch_starts": 1},
        {"name": "a start while a run of the channel runs is BUSY",
         "steps": [start, run1, "hub starts drive while run 1 runs: goal f32 1.0", "device refuses the start: BUSY"],
         "sketch_starts": 1},
        {"name": "goal errors in order, then a start the sketch refuses",
         "steps": ["hub starts drive with a goal out of range: f32 20.0", "device refuses the start: OUT_OF_RANGE",
                   "hub starts drive with a goal of the wrong length (2 bytes)", "device refuses the start: BAD_LENGTH",
                   "hub starts drive: goal f32 3.0 (the sketch refuses it)",
                   "device refuses the start: REJECTED (the start function returned false)"],
         "sketch_starts": 1},
        {"name": "bad ops and lengths",
         "steps": ["hub sends op 3 (unknown)", "device refuses an unknown op: BAD_VALUE",
                   "hub sends an empty C to a mission", "device refuses an empty C: BAD_LENGTH",
                   "hub sends a cancel of 3 bytes", "device refuses a cancel of 3 bytes: BAD_LENGTH"],
         "sketch_starts": 0},
        {"name": "cancel a running run, then again: it is not running any more",
         "steps": [start, run1, "hub reads drive's state", "device: run 1 running",
                   "hub cancels drive run 1", "device: run 1 was running, its cancel function was called",
                   "drive run 1 cancelled", "hub acknowledges: drive run 1 cancelled",
                   "hub cancels drive run 1 again", "device: run 1 is not running",
                   "hub reads drive's state again", "device: run 1 not running"],
         "sketch_starts": 1, "sketch_cancels": 1},
        {"name": "a run reports progress and succeeds; a retried M is acked again and delivered once",
         "steps": [start, run1, "drive run 1 progress f32 0.5", "hub acknowledges: drive run 1 progress f32 0.5",
                   "drive run 1 progress f32 0.5", "hub acknowledges: drive run 1 progress f32 0.5",
                   "drive run 1 progress f32 1.25", "hub acknowledges: drive run 1 progress f32 1.25",
                   "drive run 1 succeeded: f32 2.0", "hub acknowledges: drive run 1 succeeded: f32 2.0"],
         "hub_delivers": ["progress 0.5", "progress 1.25", "succeeded 2.0"]},
        {"name": "a run without goal, with void progress and a void result",
         "steps": ["hub reads home's state (no run since boot)", "device: no run since boot",
                   "hub starts home (no goal)", "device accepts the start of home: run 1",
                   "home run 1 progress (void)", "hub acknowledges: home run 1 progress (void)",
                   "home run 1 succeeded (void result)", "hub acknowledges: home run 1 succeeded (void result)"],
         "sketch_starts": 1},
        {"name": "the hub acks an update of a run it does not know and delivers nothing",
         "steps": ["drive run 9 progress f32 0.5 (a run the hub does not know)",
                   "hub acknowledges: drive run 9 progress f32 0.5 (a run the hub does not know)"],
         "hub_delivers": []},
    ]
