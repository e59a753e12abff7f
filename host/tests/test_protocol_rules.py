"""The hub against the session rules of docs/PROTOCOL.md (test/vectors/session/rules.json).

- hub_script: a scripted device on a pty handshakes and serves its descriptor; once the hub is
  connected it sends the script's frames, and the hub's ACK / NAK / hello frames and the link
  callbacks must be exactly the script's.
- string_bytes: the hub's str codec decodes bytes that are not UTF-8 with U+FFFD.
- device_script: every frame of the device scripts (which test/test_protocol_rules plays against
  the C++ device) goes through the hub's frame codec and message decoder unchanged.
"""
from __future__ import annotations

import json
import os
import select
import threading
import time
import tty
from typing import Any, Dict, List

import pytest

import hubwire
from hubwire.descriptor.cache import descriptor_digest
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame, FrameDecoder, encode_frame
from hubwire.wire.values import codec_for

RULES = os.path.join(os.path.dirname(__file__), "..", "..", "test", "vectors", "session", "rules.json")
with open(RULES) as fh:
    VECTORS: List[Dict[str, Any]] = json.load(fh)["vectors"]
DESCRIPTOR = b'{"p":1,"n":"rules","ch":[{"id":1,"n":"x","a":"rw","t":"u16"},{"id":3,"n":"bump","a":"e","t":"u8"}]}'
NONCE = 0x0BADF00D
DEADLINE = 10.0  # seconds: generous, only a broken hub gets near it


def of_kind(kind: str) -> List[Dict[str, Any]]:
    found = [v for v in VECTORS if v["kind"] == kind]
    assert found, f"no {kind} vectors in {RULES}"
    return found


class ScriptedDevice:
    """Answers hellos and chunk requests, beats every 200 ms, records every frame the hub sends."""

    def __init__(self) -> None:
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self.got: List[Frame] = []
        self.lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        os.close(self.master)
        os.close(self.slave)

    def send(self, t: int, seq: int, cid: int, payload: bytes = b"") -> None:
        os.write(self.master, encode_frame(t, seq, cid, payload))

    def hello(self, flags: int, digest: bool = True) -> None:
        h = m.Hello(1, flags | m.FLAG_DEVICE, NONCE, 32, 250, m.fnv1a32(DESCRIPTOR), len(DESCRIPTOR),
                    descriptor_digest(DESCRIPTOR) if digest else None)
        self.send(m.HELLO, 0, 0, h.pack())

    def answers(self) -> List[Frame]:
        with self.lock:
            return [f for f in self.got if f.type in (m.ACK, m.NAK, m.HELLO)]

    def _run(self) -> None:
        dec, beat, n = FrameDecoder(32), 0.0, 0
        while not self._stop.is_set():
            if select.select([self.master], [], [], 0.02)[0]:
                try:
                    data = os.read(self.master, 512)
                except OSError:
                    return
                for f in dec.feed(data):
                    with self.lock:
                        self.got.append(f)
                    if f.type == m.HELLO and not m.Hello.unpack(f.payload).is_reply:
                        self.hello(m.FLAG_REPLY)
                    elif f.type == m.CHUNK:
                        r = m.ChunkRequest.unpack(f.payload)
                        part = DESCRIPTOR[r.offset:r.offset + min(r.want, 28)]
                        self.send(m.CHUNK, f.seq, 0, m.Chunk(r.offset, len(DESCRIPTOR), part).pack())
            if time.monotonic() - beat > 0.2:
                beat, n = time.monotonic(), n + 1
                self.send(m.HEARTBEAT, n & 0xFF, 0, m.Heartbeat(n, 200, 0, 0, 0).pack())


def matches(want: Dict[str, Any], got: Frame) -> bool:
    if (got.type, got.seq, got.id) != (want["type"], want["seq"], want["id"]):
        return False
    if "hello_flags" in want:
        return (m.Hello.unpack(got.payload).flags & 3) == want["hello_flags"]
    return got.payload.hex() == want["payload"]


@pytest.mark.parametrize("v", of_kind("hub_script"), ids=lambda v: v["name"][:60])
def test_hub_script(v: Dict[str, Any], tmp_path: Any) -> None:
    dev = ScriptedDevice()
    seen: List[str] = []
    try:
        with hubwire.connect(dev.path, cache_dir=str(tmp_path)) as hub:
            hub.on("link_lost", lambda: seen.append("link_lost"))
            hub.on("link_restored", lambda: seen.append("link_restored"))
            before = len(dev.answers())
            for f in v["device"]:
                if f["type"] == m.HELLO:
                    dev.hello(f["hello_flags"] & ~m.FLAG_DEVICE, f.get("digest", True))
                else:
                    dev.send(f["type"], f["seq"], f["id"], bytes.fromhex(f["payload"]))
            want, end = v["hub_answers"], time.monotonic() + DEADLINE
            while time.monotonic() < end and (len(dev.answers()) - before < len(want) or len(seen) < len(v["app"])):
                time.sleep(0.05)
            got = dev.answers()[before:]
            time.sleep(0.1)  # the callbacks run on the hub's dispatcher thread
            assert len(got) == len(want), [(f.type, f.seq, f.id, f.payload.hex()) for f in got]
            for w, g in zip(want, got):
                assert matches(w, g), (w, g)
            assert seen == v["app"]
    finally:
        dev.close()


@pytest.mark.parametrize("v", of_kind("string_bytes"), ids=lambda v: v["name"])
def test_string_bytes(v: Dict[str, Any]) -> None:
    assert codec_for(v["type"]).decode(bytes.fromhex(v["hex"])) == v["hub_text"]


@pytest.mark.parametrize("v", of_kind("device_script"), ids=lambda v: v["name"][:60])
def test_device_script_frames_pass_the_hub_codec(v: Dict[str, Any]) -> None:
    count = 0
    for s in v["steps"]:
        # the hub's frames may be malformed on purpose; the device's must decode as messages
        for f, from_device in [(f, False) for f in s["hub"]] + [(f, True) for f in s["device"] if "payload" in f]:
            payload = bytes.fromhex(f["payload"])
            frames = FrameDecoder().feed(encode_frame(f["type"], f["seq"], f["id"], payload))
            assert frames == [Frame(f["type"], f["seq"], f["id"], payload)]
            if from_device:
                assert m.describe(frames[0])["kind"] in ("heartbeat", "ack", "nak", "event", "sample", "response")
            count += 1
    assert count > 0
