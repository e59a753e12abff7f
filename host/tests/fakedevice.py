"""A minimal scripted device on a pty, for hub tests the emulator cannot drive (wrong protocol
version, wrong descriptor hash, lost chunks, boot noise). Test helper only."""
from __future__ import annotations

import os
import select
import threading
import time
import tty
from typing import Callable, List, Optional, Tuple, Union

from hubwire.descriptor.cache import descriptor_digest
from hubwire.wire import messages as m
from hubwire.wire.frame import FrameDecoder, encode_frame

DESCRIPTOR = (b'{"p":1,"n":"fake","ch":[{"id":1,"n":"x","a":"rw","t":"u16"},'
              b'{"id":2,"n":"label","a":"r","t":"str","c":8,"d":"' + b"padding " * 20 + b'"}]}')


class FakeDevice:
    def __init__(self, descriptor: bytes = DESCRIPTOR, *, version: int = 1, announced_hash: Optional[int] = None,
                 noise: bytes = b"", max_payload: int = 32,
                 drop_chunk: Optional[Callable[[int, int], bool]] = None,
                 digest: Union[bytes, bool] = True) -> None:
        self.descriptor = descriptor
        self.version = version
        self.hash = m.fnv1a32(descriptor) if announced_hash is None else announced_hash
        #: the descriptor digest announced in the hello: True its own, False none (an older
        #: library's 16-byte hello), or any 16 bytes (a lie)
        self.digest: Optional[bytes] = (descriptor_digest(descriptor) if digest is True
                                        else None if digest is False else bytes(digest))
        #: (channel id, value) of every control received, in order
        self.writes: List[Tuple[int, int]] = []
        self.noise = noise
        self.max_payload = max_payload
        self.drop_chunk = drop_chunk or (lambda offset, nth: False)
        self.chunk_requests: dict = {}
        self.x = 0
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> "FakeDevice":
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(2)
        os.close(self.master)
        os.close(self.slave)

    def _send(self, t: int, seq: int, cid: int, payload: bytes = b"") -> None:
        os.write(self.master, encode_frame(t, seq, cid, payload))

    def _hello(self, reply: bool) -> None:
        flags = m.FLAG_DEVICE | m.FLAG_SEQ_RULES | (m.FLAG_REPLY if reply else 0)
        h = m.Hello(self.version, flags, 0x1234567, self.max_payload, 250, self.hash, len(self.descriptor),
                    digest=self.digest)
        self._send(m.HELLO, 0, 0, h.pack())

    def reflash(self, descriptor: bytes) -> None:
        """New firmware, same nonce (a board without nonce entropy): announce it."""
        self.descriptor = descriptor
        self.hash = m.fnv1a32(descriptor)
        if self.digest is not None:
            self.digest = descriptor_digest(descriptor)
        self._hello(False)

    def _run(self) -> None:
        dec = FrameDecoder(self.max_payload)
        linked = False
        beat = 0.0
        n = 0
        while not self._stop.is_set():
            r, _, _ = select.select([self.master], [], [], 0.02)
            if r:
                try:
                    data = os.read(self.master, 512)
                except OSError:
                    return
                if self.noise:  # the hub opened the port: the board "boots" and prints noise first
                    os.write(self.master, self.noise)
                    self.noise = b""
                    continue
                for f in dec.feed(data):
                    if f.type == m.HELLO:
                        h = m.Hello.unpack(f.payload)
                        if not h.is_reply:
                            self._hello(True)
                        linked = True
                    elif f.type == m.CHUNK:
                        req = m.ChunkRequest.unpack(f.payload)
                        nth = self.chunk_requests.get(req.offset, 0)
                        self.chunk_requests[req.offset] = nth + 1
                        if self.drop_chunk(req.offset, nth):
                            continue
                        k = min(req.want, self.max_payload - 4, 251, len(self.descriptor) - req.offset)
                        data = self.descriptor[req.offset:req.offset + k]
                        self._send(m.CHUNK, f.seq, 0, m.Chunk(req.offset, len(self.descriptor), data).pack())
                    elif f.type == m.REQUEST:
                        self._send(m.RESPONSE, f.seq, f.id, self.x.to_bytes(2, "little"))
                    elif f.type == m.CONTROL:
                        self.x = int.from_bytes(f.payload, "little")
                        self.writes.append((f.id, self.x))
                        self._send(m.ACK, f.seq, f.id)
            if linked and time.monotonic() - beat > 0.25:
                beat = time.monotonic()
                n += 1
                self._send(m.HEARTBEAT, n & 0xFF, 0, m.Heartbeat(n, 250, 0, 0, 0).pack())
