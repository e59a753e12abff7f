"""Session rules of docs/PROTOCOL.md section 8 as vectors: test/vectors/session/rules.json.

Written by generate.py (which imports this module). The expectations are written out by hand from
the document, not computed by either implementation; test/test_protocol_rules (C++, the device) and
host/tests/test_protocol_rules.py (Python, the hub) play them. Kinds:

- device_script: steps played against a device built with the defaults and the channels
  DEVICE_CHANNELS names. Each step: advance the clock by advance_ms, feed the hub frames, emit
  the event if any, run update() once, and compare every frame the device wrote, in order, with
  device (a device hello is compared by hello_flags & 3 and, when digest is given, by its size: 32
  bytes with the digest, 16 without; its nonce and hash vary).
- hub_script: frames a device sends once the hub is connected (a hello among them is the device's
  own, same nonce, with hello_flags); hub_answers are the frames of type ACK, NAK and hello the hub
  must send back, in order; app the link callbacks the application sees.
- string_bytes: a str payload, UTF-8 or not: the device stores and reads back the bytes as they
  are; the hub decodes them to hub_text (each invalid sequence becomes U+FFFD).
"""
from __future__ import annotations

from typing import Any, Dict, List, Optional

from hubwire.wire import messages as m

DEVICE_CHANNELS = ('1 "level" u8 readable writable streamable, range 0..100; 2 "name" str[4] readable '
                   'writable; 3 "beep" control taking u8 that refuses 0; 4 "bump" event u8')
LEVEL, NAME, BEEP, BUMP = 1, 2, 3, 4
UNKNOWN_TYPE = 0x58  # 'X': no message has this type


def fr(t: int, seq: int, cid: int, payload: bytes = b"") -> Dict[str, Any]:
    return {"type": t, "seq": seq, "id": cid, "payload": payload.hex()}


def hub_hello(nonce: int, version: int = 1) -> Dict[str, Any]:
    return fr(m.HELLO, 0, 0, m.Hello(version, 0, nonce, 255, 250).pack())


def device_hello(reply: bool, digest: bool = True) -> Dict[str, Any]:
    """A device hello, judged by its flags; ``digest``: whether it carries the descriptor digest
    (hello bytes 16..31, which a device sends once it has heard a hub that takes them)."""
    return {"type": m.HELLO, "seq": 0, "id": 0, "hello_flags": m.FLAG_DEVICE | (m.FLAG_REPLY if reply else 0),
            "digest": digest}


def beat(counter: int, since: int, dropped: int = 0) -> Dict[str, Any]:
    return fr(m.HEARTBEAT, counter & 0xFF, 0, m.Heartbeat(counter, since, 0, 0, dropped).pack())


def nak(seq: int, cid: int, code: int) -> Dict[str, Any]:
    return fr(m.NAK, seq, cid, m.Nak(code).pack())


def step(device: List[Dict[str, Any]], hub: Optional[List[Dict[str, Any]]] = None, advance_ms: int = 0,
         emit: Optional[bytes] = None) -> Dict[str, Any]:
    s: Dict[str, Any] = {"advance_ms": advance_ms, "hub": hub or []}
    if emit is not None:
        s["emit"] = {"id": BUMP, "value": emit.hex()}
    s["device"] = device
    return s


LINK = step([device_hello(True), beat(1, 0)], [hub_hello(0x51)])
N = m.NakCode


def device_scripts() -> List[Dict[str, Any]]:
    out: List[Dict[str, Any]] = []

    def add(name: str, rule: str, steps: List[Dict[str, Any]]) -> None:
        out.append({"name": name, "kind": "device_script", "rule": rule, "steps": steps})

    add("a NAK of an event ends it like an ACK: no retry, the next event takes the next seq", "4.4", [
        LINK,
        step([fr(m.EVENT, 1, BUMP, b"\x05")], emit=b"\x05"),
        step([], [nak(1, BUMP, N.REJECTED)]),
        step([], advance_ms=150),
        step([fr(m.EVENT, 2, BUMP, b"\x06")], emit=b"\x06"),
    ])
    add("errors are judged in a fixed order", "5", [
        step([nak(9, 0, N.UNKNOWN_TYPE)], [fr(UNKNOWN_TYPE, 9, 0)]),
        step([nak(10, 99, N.NOT_LINKED)], [fr(m.REQUEST, 10, 99, b"\x00")]),
        step([device_hello(True), beat(1, 0, dropped=1)], [hub_hello(0x52)]),
        step([nak(11, 99, N.UNKNOWN_CHANNEL)], [fr(m.CONTROL, 11, 99)]),
        step([nak(12, BUMP, N.NOT_WRITABLE)], [fr(m.CONTROL, 12, BUMP, b"\x01\x02")]),
        step([nak(13, NAME, N.BAD_VALUE)], [fr(m.CONTROL, 13, NAME, b"\x09")]),
        step([nak(14, NAME, N.BAD_LENGTH)], [fr(m.CONTROL, 14, NAME, b"\x02\x41")]),
        step([nak(15, LEVEL, N.BAD_LENGTH)], [fr(m.CONTROL, 15, LEVEL, b"\x65\x65")]),
        step([nak(16, LEVEL, N.OUT_OF_RANGE)], [fr(m.CONTROL, 16, LEVEL, b"\x65")]),
        step([nak(17, BEEP, N.REJECTED)], [fr(m.CONTROL, 17, BEEP, b"\x00")]),
        step([nak(18, BEEP, N.NOT_READABLE)], [fr(m.REQUEST, 18, BEEP, b"\x00")]),
        step([nak(19, NAME, N.NOT_STREAMABLE)], [fr(m.SUBSCRIBE, 19, NAME, b"\x01")]),
        step([nak(20, LEVEL, N.BAD_LENGTH)], [fr(m.SUBSCRIBE, 20, LEVEL, b"\x01")]),
        step([nak(21, 0, N.BAD_LENGTH)], [fr(m.CHUNK, 21, 0, b"\xff\xff")]),
        step([nak(22, 0, N.BAD_OFFSET)], [fr(m.CHUNK, 22, 0, b"\xff\xff\x10")]),
    ])
    add("samples: the first has seq 0 and dt 0; a new interval keeps seq and times dt from the previous "
        "sample; a cancel then a subscribe starts again at 0", "3.7", [
        LINK,
        step([fr(m.ACK, 1, LEVEL, b"\x14\x00"), fr(m.SAMPLE, 0, LEVEL, b"\x00\x00\x00")],
             [fr(m.SUBSCRIBE, 1, LEVEL, b"\x14\x00")]),
        step([fr(m.SAMPLE, 1, LEVEL, b"\x14\x00\x00")], advance_ms=20),
        step([fr(m.ACK, 2, LEVEL, b"\x32\x00"), fr(m.SAMPLE, 2, LEVEL, b"\x05\x00\x00")],
             [fr(m.SUBSCRIBE, 2, LEVEL, b"\x32\x00")], advance_ms=5),
        step([fr(m.SAMPLE, 3, LEVEL, b"\x32\x00\x00")], advance_ms=50),
        step([fr(m.ACK, 3, LEVEL, b"\x00\x00")], [fr(m.SUBSCRIBE, 3, LEVEL, b"\x00\x00")]),
        step([fr(m.ACK, 4, LEVEL, b"\x14\x00"), fr(m.SAMPLE, 0, LEVEL, b"\x00\x00\x00")],
             [fr(m.SUBSCRIBE, 4, LEVEL, b"\x14\x00")], advance_ms=10),
    ])
    add("heartbeats: since_ms is 0 in the first after each link-up; the counter runs on from boot", "3.2", [
        LINK,
        step([beat(2, 250)], advance_ms=250),
        step([beat(3, 250)], advance_ms=250),
        step([beat(4, 250)], advance_ms=250),
        step([], advance_ms=250),  # 1000 ms without a hub frame: link lost, nothing sent
        step([device_hello(True), beat(5, 0)], [hub_hello(0x51)], advance_ms=100),
    ])
    add("a hello of another version while linked is answered, keeps the link and proves the hub alive",
        "8", [
            LINK,
            step([device_hello(True), beat(2, 500)], [hub_hello(0x51, version=2)], advance_ms=500),
            step([beat(3, 600)], advance_ms=600),
            step([fr(m.RESPONSE, 1, LEVEL, b"\x00")], [fr(m.REQUEST, 1, LEVEL)]),
        ])
    add("any valid frame proves the hub alive, an ACK that matches no event too", "4.3", [
        LINK,
        step([beat(2, 900)], [fr(m.ACK, 200, BUMP)], advance_ms=900),
        step([beat(3, 900)], advance_ms=900),
        step([], advance_ms=100),  # 1000 ms after the ACK: link lost
        step([nak(1, LEVEL, N.NOT_LINKED)], [fr(m.REQUEST, 1, LEVEL)]),
    ])
    add("an unlinked device answers a heartbeat with its hello, REPLY clear", "4.2", [
        # freshly booted: it has heard no hub that takes 32 bytes, so no digest (7.1)
        step([device_hello(False, digest=False)], [fr(m.HEARTBEAT, 1, 0, m.Heartbeat(1, 0, 0, 0, 0).pack())]),
        LINK,
    ])
    add("after a link loss (no reset) the device's hello answering a heartbeat carries the digest", "7.1", [
        LINK,  # the hub's hello takes 255 bytes: the device keeps that across the link loss
        step([beat(2, 250)], advance_ms=250),
        step([beat(3, 250)], advance_ms=250),
        step([beat(4, 250)], advance_ms=250),
        step([], advance_ms=250),  # 1000 ms without a hub frame: link lost
        step([device_hello(False, digest=True)], [fr(m.HEARTBEAT, 5, 0, m.Heartbeat(5, 250, 0, 0, 0).pack())]),
        step([device_hello(True), beat(5, 0)], [hub_hello(0x51)], advance_ms=100),
    ])
    add("a hub nonce of 0 is taken like any other", "3.1", [
        step([device_hello(True), beat(1, 0)], [hub_hello(0)]),
        step([fr(m.RESPONSE, 1, LEVEL, b"\x00")], [fr(m.REQUEST, 1, LEVEL)]),
    ])
    add("a string that is not UTF-8 is stored and read back as sent", "6", [
        LINK,
        step([fr(m.ACK, 1, NAME)], [fr(m.CONTROL, 1, NAME, b"\x02\xff\xfe")]),
        step([fr(m.RESPONSE, 2, NAME, b"\x02\xff\xfe")], [fr(m.REQUEST, 2, NAME)]),
    ])
    return out


def hub_scripts() -> List[Dict[str, Any]]:
    # The hub's device (see host/tests/test_protocol_rules.py): channel 1 "x" u16 rw, 3 "bump" event u8.
    return [
        {"name": "the hub acks every event, a repeated, unknown or malformed one too, and never NAKs one",
         "kind": "hub_script", "rule": "4.4",
         "device": [fr(m.EVENT, 5, 3, b"\x01"), fr(m.EVENT, 5, 3, b"\x01"), fr(m.EVENT, 6, 9, b"\x01"),
                    fr(m.EVENT, 7, 3, b"\x01\x02")],
         "hub_answers": [fr(m.ACK, 5, 3), fr(m.ACK, 5, 3), fr(m.ACK, 6, 9), fr(m.ACK, 7, 3)],
         "app": []},
        {"name": "a linked device's unsolicited hello (it lost the link) is answered with a REPLY hello; "
                 "the application sees link lost, then restored",
         "kind": "hub_script", "rule": "8",
         "device": [device_hello(False)],
         "hub_answers": [{"type": m.HELLO, "seq": 0, "id": 0, "hello_flags": m.FLAG_REPLY}],
         "app": ["link_lost", "link_restored"]},
        {"name": "an unsolicited hello without the digest from a device that takes 32 bytes is answered with "
                 "a hello with REPLY clear, and the device's answer (with the digest) is the one acted on",
         "kind": "hub_script", "rule": "7.1",
         "device": [device_hello(False, digest=False)],
         "hub_answers": [{"type": m.HELLO, "seq": 0, "id": 0, "hello_flags": 0}],
         "app": ["link_lost", "link_restored"]},
    ]


def string_bytes() -> List[Dict[str, Any]]:
    return [{"name": "str[4] holding ff fe", "kind": "string_bytes", "type": {"t": "str", "c": 4},
             "hex": "02fffe", "hub_text": "\ufffd\ufffd"},
            {"name": "str[4] holding valid UTF-8 (A, e acute)", "kind": "string_bytes", "type": {"t": "str", "c": 4},
             "hex": "0341c3a9", "hub_text": "A\u00e9"},
            {"name": "str[4] holding the first byte of a two-byte sequence", "kind": "string_bytes",
             "type": {"t": "str", "c": 4}, "hex": "0241c3", "hub_text": "A\ufffd"}]


def gen() -> Dict[str, Any]:
    return {"description": __doc__.strip().split("\n\n", 1)[1] + "\n\nDevice channels: " + DEVICE_CHANNELS,
            "vectors": device_scripts() + hub_scripts() + string_bytes()}
