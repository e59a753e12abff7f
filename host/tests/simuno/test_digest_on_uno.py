"""Every example, compiled by avr-g++ for the Uno and run on the simulated Uno, announces in its hello
the first 16 bytes of its descriptor's SHA-256 (PROTOCOL.md 3.1): the digest the compiler worked out
(with AVR's 16-bit size_t) is checked here against hashlib over the descriptor the board sends.

Plain frames over the port, so that only the wire layer is involved. Needs `make simuno uno-firmware`.
"""
from __future__ import annotations

import hashlib
import os
import time
from typing import Any, List, Optional

import pytest
import serial

from hubwire.wire import messages as m
from hubwire.wire.frame import Frame, FrameDecoder, encode_frame

from .conftest import REPO, Simuno, example_elf

EXAMPLES = sorted(d for d in os.listdir(os.path.join(REPO, "examples"))
                  if os.path.isfile(os.path.join(REPO, "examples", d, d + ".ino")))
HUB_MAX = 255


class RawHub:
    """Frames to and from the board, nothing more."""

    def __init__(self, port: serial.Serial) -> None:
        self.port = port
        self.decoder = FrameDecoder(HUB_MAX)
        self.pending: List[Frame] = []

    def send(self, type_: int, seq: int, payload: bytes) -> None:
        self.port.write(encode_frame(type_, seq, 0, payload))

    def next(self, wanted: int, timeout: float) -> Optional[Frame]:
        """The next frame of type ``wanted`` (others are dropped), or None after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            while self.pending:
                f = self.pending.pop(0)
                if f.type == wanted:
                    return f
            self.pending.extend(self.decoder.feed(self.port.read(64)))
        return None


@pytest.mark.parametrize("name", EXAMPLES)
def test_hello_digest_is_the_sha256_of_the_descriptor_sent(name: str, simuno_build: tuple, tmp_path: Any) -> None:
    elf = example_elf(name)
    if not os.path.isfile(elf):
        pytest.fail(f"{elf} missing; build it with `make uno-firmware`", pytrace=False)
    sim = Simuno(simuno_build[0], elf, str(tmp_path / "uno"), str(tmp_path / "simuno.log"))
    sim.start()
    try:
        with serial.Serial(sim.link, 115200, timeout=0.05) as port:
            hub = RawHub(port)
            hello = m.Hello(1, 0, 0x600DF00D, HUB_MAX, 250).pack()
            reply = None
            for _ in range(100):  # a hello every 100 ms until the board, past its bootloader, answers
                hub.send(m.HELLO, 0, hello)
                reply = hub.next(m.HELLO, 0.1)
                if reply is not None:
                    break
            assert reply is not None, sim.log_text()
            h = m.Hello.unpack(reply.payload)
            assert h.is_device and len(reply.payload) == m.Hello.SIZE_WITH_DIGEST
            descriptor = b""
            seq = 0
            while len(descriptor) < h.descriptor_length:
                f = None
                for _ in range(5):  # a slow (busy) simulation: ask again, as the hub would
                    seq = (seq + 1) % 256
                    hub.send(m.CHUNK, seq, m.ChunkRequest(len(descriptor), 255).pack())
                    f = hub.next(m.CHUNK, 2.0)
                    while f is not None and f.seq != seq:  # a late answer to an earlier request
                        f = hub.next(m.CHUNK, 2.0)
                    if f is not None:
                        break
                assert f is not None, f"no chunk at {len(descriptor)}"
                chunk = m.Chunk.unpack(f.payload)
                assert chunk.offset == len(descriptor) and chunk.data
                descriptor += chunk.data
    finally:
        assert sim.stop() == 0, sim.log_text()
    assert len(descriptor) == h.descriptor_length
    assert m.fnv1a32(descriptor) == h.descriptor_hash
    assert h.digest == hashlib.sha256(descriptor).digest()[:16]
