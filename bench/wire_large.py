#!/usr/bin/env python3
"""Row 3b: wire cost of large values (fragments `F`), a variable-length List and one mission run,
computed with the hub's own codec (hubwire.session.fragments.encode_message, hubwire.wire), as row 3.

    python bench/wire_large.py [--progress 10]

Deterministic: the same figures on every machine. A device's answer is cut to what the hub accepts
(255) and what the device itself can hold (its HUBWIRE_MAX_PAYLOAD), as PROTOCOL.md 12.2 says.
"""
from __future__ import annotations

import argparse
from typing import List, Tuple

from common import md_table, row, save

from hubwire.session.fragments import encode_message
from hubwire.wire import messages as m
from hubwire.wire.frame import encode_frame
from hubwire.wire.missions import MissionKind, MissionUpdate, start_payload
from hubwire.wire.values import codec_for

HUB_ACCEPTS = 255
#: examples/LargeValues' profile (200 B) and extras/tests/Large1K's big (1024 B), as they declare them
PROFILE = {"t": "struct", "f": [{"n": "gain", "t": "f32", "c": 20}, {"n": "table", "t": "i16", "c": 40},
                                {"n": "name", "t": "u8", "c": 40}]}
BIG = {"t": "struct", "f": [{"n": "words", "t": "u32", "c": 200}, {"n": "f", "t": "f32", "c": 56}]}
PATH = {"t": "i16", "vc": 12}


def frames(wire: bytes) -> int:
    return wire.count(b"\x00")  # every frame ends with its one 00 delimiter (COBS)


def write_read(value: bytes, device_max: int) -> Tuple[bytes, bytes, bytes, bytes]:
    """Wire bytes of: the hub's `C`, the device's ACK, the hub's `R`, the device's `r`."""
    c = encode_message(m.CONTROL, 9, 1, value, min(device_max, HUB_ACCEPTS))
    ack = encode_frame(m.ACK, 9, 1)
    r = encode_frame(m.REQUEST, 10, 1)
    resp = encode_message(m.RESPONSE, 10, 1, value, min(HUB_ACCEPTS, device_max))
    return c, ack, r, resp


def mission_run(progress: int) -> List[Tuple[str, bytes]]:
    """One run of examples/Missions' drive (f32 goal, f32 progress, f32 result) with ``progress`` updates."""
    f32 = codec_for({"t": "f32"})
    out = [("`C` start (op + f32 goal)", encode_frame(m.CONTROL, 1, 1, start_payload(f32.encode(1.0)))),
           ("`r` run number", encode_frame(m.RESPONSE, 1, 1, b"\x01"))]
    for i in range(progress):
        out.append(("`M` progress (f32)", encode_frame(m.MISSION, 2 + i, 1,
                                                         MissionUpdate(1, MissionKind.PROGRESS, f32.encode(0.1)).pack())))
        out.append(("ACK", encode_frame(m.ACK, 2 + i, 1)))
    out.append(("`M` succeeded (f32 result)", encode_frame(m.MISSION, 2 + progress, 1,
                                                            MissionUpdate(1, MissionKind.SUCCEEDED, f32.encode(1.0)).pack())))
    out.append(("ACK", encode_frame(m.ACK, 2 + progress, 1)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--progress", type=int, default=10, help="progress updates in the mission run")
    a = ap.parse_args()
    profile = codec_for(PROFILE)
    big = codec_for(BIG)
    lines = []
    ratios = {}
    cases = [("200 B struct, Uno (accepts 32)", profile.encode(profile.decode(bytes(range(200)))), 32),
             ("1 KB struct, device accepting 255", big.encode(big.decode(bytes(i & 0xFF for i in range(1024)))), 255),
             ("1 KB struct, emulator default (accepts 32)", big.encode(big.decode(bytes(1024))), 32)]
    for name, value, dev_max in cases:
        c, ack, r, resp = write_read(value, dev_max)
        w, rd = len(c) + len(ack), len(r) + len(resp)
        ratios[name] = (w / len(value), rd / len(value))
        lines.append([name, len(value), f"{frames(c)} `F` + ACK = {frames(c) + 1}", f"{w} B ({w / len(value):.2f}x)",
                      f"`R` + {frames(resp)} `F` = {frames(resp) + 1}", f"{rd} B ({rd / len(value):.2f}x)"])
    path = codec_for(PATH)
    pv = path.encode(list(range(-600, 600, 100)))
    c, ack, r, resp = write_read(pv, 32)
    lines.append([f"List i16[<=12], 12 elements ({len(pv)} B: count + 24)", len(pv), "`C` + ACK = 2",
                  f"{len(c) + len(ack)} B ({(len(c) + len(ack)) / 24:.2f}x of 24 B)", "`R` + `r` = 2",
                  f"{len(r) + len(resp)} B ({(len(r) + len(resp)) / 24:.2f}x of 24 B)"])
    run = mission_run(a.progress)
    run_bytes = sum(len(b) for _, b in run)
    per_update = len(run[2][1]) + len(run[3][1])
    fixed = run_bytes - a.progress * per_update
    mlines = [[k, len(b)] for k, b in run[:4]] + [[k, len(b)] for k, b in run[-2:]]
    u200 = ratios[cases[0][0]]
    k1 = ratios[cases[1][0]]
    details = f"""### Row 3b: large values in fragments, a List, a mission run (hub codec, deterministic)

Writes: the hub's `C` (one frame, or `F` fragments filled to the receiver's accepted payload minus the
5-byte fragment header) and the device's ACK. Reads: `R` and the device's `r` (fragments cut to the
smaller of what the hub accepts, 255, and the device's own frame). Ratio = wire bytes / value bytes.

{md_table(["value", "value B", "write frames", "write wire B", "read frames", "read wire B"], lines)}

A fragment costs the 7 bytes of its frame plus its 5-byte header (type, offset, total): 12 bytes per
27 value bytes on the Uno, 12 per 250 (13 when 254 value bytes in a row hold no 00: COBS) on a device accepting 255.

One mission run (examples/Missions' `drive`: f32 goal, progress and result) with N progress updates:
**{fixed} + {per_update} x N bytes, 4 + 2 x N frames** (N = {a.progress}: {run_bytes} B, {4 + 2 * a.progress} frames).
Latest progress wins on the device, so N is at most one per progress the sketch reports and fewer
when the line is slower than the sketch.

{md_table(["frame", "wire B"], mlines)}
"""
    rows = [row("3b. Wire cost of a 200 B write / read on the Uno (fragments)", "",
                f"{u200[0]:.2f}x / {u200[1]:.2f}x the value ({lines[0][2]}; {lines[0][4]})", None,
                "python bench/wire_large.py", "8 fragments of 27 B each way"),
            row("3b. Wire cost of a 1 KB write / read, device accepting 255", "",
                f"{k1[0]:.2f}x / {k1[1]:.2f}x the value ({lines[1][2]}; {lines[1][4]})", None,
                "python bench/wire_large.py"),
            row("3b. Mission run with N progress updates", "", f"{fixed} + {per_update} x N B, 4 + 2N frames", None,
                "python bench/wire_large.py", "each `M` is ACKed; start and final add 4 frames")]
    save("wire_large", rows, details, {"ratios": ratios, "mission_fixed": fixed, "mission_per_update": per_update})


if __name__ == "__main__":
    main()
