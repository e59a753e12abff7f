"""Large values and variable-length arrays (issue 22, docs/PROTOCOL.md 6 and 12): test/vectors/large/frames.json.

Written by generate.py (which imports this module). A folder of its own, like both/: the wire
suites load test/vectors/*.json, and these frames carry a `direction` besides the fields of
frames.json (`"hub"`: the hub sends it; `"device"`: the device sends it).

The device of these vectors accepts 32-byte payloads (the default `HUBWIRE_MAX_PAYLOAD`) and
declares the channels in `channels`: `big`, 200 bytes (`u8[200]`), readable, writable and
streamable; `path`, a list of up to 8 `i16` within -1000..1000. Fragments of a message to that
device carry 32 - 5 = 27 bytes; the device's own fragments likewise 27 bytes (its frame holds 32).

`vectors` pins single frames (`message.kind` `fragment`: `carries` the carried type, `offset`,
`total`, `data` hex; a window request, PROTOCOL.md 12.8, is a `request` whose `value` is its
[u16 offset, u16 count], its answer a `response` [u16 offset, u16 total, u32 hash, bytes]).
`exchanges` are what a device does with them, in order: every frame of
`send` goes to the device (a freshly linked device; the hub's transaction seq as given), and the
device answers exactly the frames of `answer`, in order, and no other; `dropped` is how much the
device's `dropped` counter grows (what its next heartbeat reports); `value` (hex) is what the
channel holds afterwards.
"""
from __future__ import annotations

import struct
from typing import Any, Dict, List

from hubwire.wire import messages as m
from hubwire.wire.frame import FrameDecoder, encode_frame

MAX_PAYLOAD = 32
STEP = MAX_PAYLOAD - m.Fragment.HEADER
BIG_ID, PATH_ID = 1, 2
CHANNELS = [{"id": BIG_ID, "n": "big", "a": "rws", "t": "u8", "c": 200},
            {"id": PATH_ID, "n": "path", "a": "rw", "t": "i16", "vc": 8, "min": -1000, "max": 1000}]
# zeros included, so that COBS has blocks to end inside fragments
BIG = bytes((i * 37 + 11) % 256 if i % 50 else 0 for i in range(200))
INITIAL = bytes(200)


def split(t: int, payload: bytes) -> List[bytes]:
    """The fragment payloads of a message of type ``t`` for a 32-byte receiver, offset 0 first."""
    return [m.Fragment(t, off, len(payload), payload[off:off + STEP]).pack() for off in range(0, len(payload), STEP)]


def gen() -> Dict[str, Any]:
    vectors: List[Dict[str, Any]] = []

    def add(name: str, direction: str, t: int, seq: int, cid: int, payload: bytes) -> str:
        wire = encode_frame(t, seq, cid, payload)
        (f,) = FrameDecoder(255).feed(wire)
        assert f == (t, seq, cid, payload), name
        vectors.append({"name": name, "direction": direction, "type": t, "seq": seq, "id": cid,
                        "payload": payload.hex(), "wire": wire.hex(), "message": m.describe(f)})
        return name

    def add_split(what: str, direction: str, t: int, seq: int, cid: int, payload: bytes) -> List[str]:
        parts = split(t, payload)
        return [add(f"{what}, fragment {i + 1} of {len(parts)}", direction, m.FRAGMENT, seq, cid, p)
                for i, p in enumerate(parts)]

    exchanges: List[Dict[str, Any]] = []

    def exchange(name: str, send: List[str], answer: List[str], dropped: int = 0, value: Any = None) -> None:
        known = {v["name"] for v in vectors}
        assert all(n in known for n in send + answer), name
        e: Dict[str, Any] = {"name": name, "send": send, "answer": answer, "dropped": dropped}
        if value is not None:
            e["value"] = {"channel": value[0], "hex": value[1].hex()}
        exchanges.append(e)

    write = add_split("hub writes big (200 bytes, seq 0x10)", "hub", m.CONTROL, 0x10, BIG_ID, BIG)
    assert len(write) == 8 and len(bytes.fromhex(vectors[0]["payload"])) == MAX_PAYLOAD
    ack = add("device acknowledges the write of big", "device", m.ACK, 0x10, BIG_ID, b"")
    exchange("a 200-byte write in 8 fragments is applied and acknowledged", write, [ack], value=(BIG_ID, BIG))
    exchange("a retried large write (same seq, every fragment again) is answered again, not applied again",
             write + write, [ack, ack], value=(BIG_ID, BIG))

    read = add("hub reads big (seq 0x11)", "hub", m.REQUEST, 0x11, BIG_ID, b"")
    answer = add_split("device answers the read of big (seq 0x11)", "device", m.RESPONSE, 0x11, BIG_ID, BIG)
    exchange("a large read is answered in fragments, back to back", write + [read], [ack] + answer,
             value=(BIG_ID, BIG))
    # a window of the value (PROTOCOL.md 12.8): one frame, 32 - 8 = 24 bytes of it
    win = add("hub asks for a window of big: 100 bytes from offset 50 (seq 0x12)", "hub", m.REQUEST, 0x12, BIG_ID,
              struct.pack("<HH", 50, 100))
    window = add("device answers the window: offset 50, total 200, FNV-1a of all of big, bytes 50..73 (seq 0x12)",
                 "device", m.RESPONSE, 0x12, BIG_ID, struct.pack("<HHI", 50, 200, m.fnv1a32(BIG)) + BIG[50:74])
    exchange("a window of a large value is one frame: what the frame holds, the value's total and hash",
             write + [win], [ack, window], value=(BIG_ID, BIG))
    past = add("hub asks for a window of big past its end (seq 0x13)", "hub", m.REQUEST, 0x13, BIG_ID,
               struct.pack("<HH", 201, 4))
    bad = add("device refuses the window past the end: BAD_OFFSET (seq 0x13)", "device", m.NAK, 0x13, BIG_ID,
              bytes((m.NakCode.BAD_OFFSET,)))
    exchange("a window past the end of the value is BAD_OFFSET", [past], [bad])
    sample = add_split("device streams a sample of big (sample seq 0, dt 0)", "device", m.SAMPLE, 0, BIG_ID,
                       struct.pack("<H", 0) + BIG)
    assert len(sample) == 8

    skip = write[:1] + write[2:]
    exchange("a fragment whose offset skips ahead is dropped and the write abandoned: nothing applied, "
             "no answer (the hub retries)", skip, [], dropped=len(skip) - 1, value=(BIG_ID, INITIAL))
    again = add_split("hub writes big again (seq 0x12)", "hub", m.CONTROL, 0x12, BIG_ID, BIG)
    ack2 = add("device acknowledges the write of big (seq 0x12)", "device", m.ACK, 0x12, BIG_ID, b"")
    exchange("a fragment of another message (seq) abandons the reassembly in progress",
             write[:3] + again[3:4] + again, [ack2], dropped=1, value=(BIG_ID, BIG))

    over = BIG + b"\x01"
    too_long = add("hub writes 201 bytes to big: the first fragment (seq 0x13)", "hub", m.FRAGMENT, 0x13, BIG_ID,
                   split(m.CONTROL, over)[0])
    rest = [add(f"hub writes 201 bytes to big: fragment {i + 2} of 8", "hub", m.FRAGMENT, 0x13, BIG_ID, p)
            for i, p in enumerate(split(m.CONTROL, over)[1:])]
    nak = add("device refuses a total over its capacity: NAK BAD_LENGTH", "device", m.NAK, 0x13, BIG_ID,
              bytes((m.NakCode.BAD_LENGTH,)))
    exchange("a total over the channel's size is refused at the first fragment; the rest are dropped",
             [too_long] + rest, [nak], dropped=len(rest), value=(BIG_ID, INITIAL))

    # variable-length arrays: a count byte, then the elements (one frame: 1 + 8 * 2 bytes at most)
    lst = bytes((3,)) + struct.pack("<3h", 1, -2, 1000)
    w = add("hub writes path = [1, -2, 1000] (seq 0x20)", "hub", m.CONTROL, 0x20, PATH_ID, lst)
    a = add("device acknowledges the write of path", "device", m.ACK, 0x20, PATH_ID, b"")
    r = add("hub reads path (seq 0x21)", "hub", m.REQUEST, 0x21, PATH_ID, b"")
    rr = add("device answers path = [1, -2, 1000]", "device", m.RESPONSE, 0x21, PATH_ID, lst)
    exchange("a list is written and read back with its count", [w, r], [a, rr], value=(PATH_ID, lst))
    e = add("hub writes path = [] (seq 0x22)", "hub", m.CONTROL, 0x22, PATH_ID, b"\x00")
    ea = add("device acknowledges the empty list", "device", m.ACK, 0x22, PATH_ID, b"")
    exchange("an empty list is a count of 0", [e], [ea], value=(PATH_ID, b"\x00"))
    refusals = [
        (0x23, bytes((9,)) + bytes(18), "BAD_VALUE", "count 9 over the capacity 8"),
        (0x24, bytes((9,)) + bytes(2), "BAD_VALUE", "count 9 over the capacity, payload short too"),
        (0x25, bytes((2,)) + bytes(2), "BAD_LENGTH", "count 2, one element"),
        (0x26, bytes((1,)) + bytes(4), "BAD_LENGTH", "count 1, two elements"),
        (0x27, b"", "BAD_LENGTH", "no count byte"),
        (0x28, bytes((2,)) + struct.pack("<2h", 1001, 5000), "OUT_OF_RANGE", "count 2, first element 1001"),
        (0x29, bytes((2,)) + struct.pack("<2h", 5, -1001), "OUT_OF_RANGE", "count 2, second element -1001"),
    ]
    for seq, payload, code, what in refusals:
        bad = add(f"hub writes path: {what} (seq 0x{seq:02x})", "hub", m.CONTROL, seq, PATH_ID, payload)
        no = add(f"device refuses path, {what}: NAK {code}", "device", m.NAK, seq, PATH_ID,
                 bytes((m.NakCode[code],)))
        exchange(f"path: {what} is {code}, nothing stored", [w, bad], [a, no], value=(PATH_ID, lst))

    return {"description": "Large values in fragments `F` and variable-length arrays (docs/PROTOCOL.md 6 and 12) "
                           "for a device accepting 32-byte payloads; `direction` is who sends the frame; "
                           "`exchanges`: frames sent to a freshly linked device and its exact answers.",
            "max_payload": MAX_PAYLOAD, "channels": CHANNELS, "big": BIG.hex(),
            "vectors": vectors, "exchanges": exchanges}
