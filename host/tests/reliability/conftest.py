"""Fixtures for the reliability tests: the emulator, the fault-injecting proxy, a scripted hostile
device on a pty, and resource snapshots (threads, file descriptors) to catch leaks."""
from __future__ import annotations

import os
import select
import subprocess
import threading
import time
import tty
from typing import Any, Callable, Iterator, List, Optional, Set

import pytest

from hubwire.testing import emulator_binary
from hubwire.testing.faultlink import FaultLink, Faults, FaultyTransport, stop_process  # noqa: F401 - for the tests
from hubwire.wire import messages as m
from hubwire.wire.frame import FrameDecoder, encode_frame

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


class Emu:
    """The Rover emulator on a pty linked at ``link``; stop() removes the link, start() brings it back."""

    def __init__(self, link: str) -> None:
        self.link = link
        self.proc: Optional[subprocess.Popen] = None

    def start(self) -> "Emu":
        assert self.proc is None
        self.proc = subprocess.Popen([emulator_binary(), "--link", self.link], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
        assert self.proc.stdout is not None
        r, _, _ = select.select([self.proc.stdout], [], [], 10)
        line = self.proc.stdout.readline().decode().strip() if r else ""
        if line != f"READY {self.link}":
            self.kill()
            raise RuntimeError(f"emulator said {line!r}")
        return self

    def stop(self) -> None:
        """SIGTERM: the emulator closes its pty and removes its link."""
        if self.proc is None:
            return
        p, self.proc = self.proc, None
        stop_process(p)
        if os.path.lexists(self.link):
            os.unlink(self.link)

    def kill(self) -> None:
        """SIGKILL (no clean-up by the process) and remove the link ourselves."""
        if self.proc is not None:
            p, self.proc = self.proc, None
            p.kill()
            p.wait(5)
        if os.path.lexists(self.link):
            os.unlink(self.link)


@pytest.fixture
def emulator_bin() -> str:
    path = emulator_binary()
    if not os.access(path, os.X_OK):
        pytest.fail(f"device emulator not found at {path}: build it with `make emulator`", pytrace=False)
    return path


@pytest.fixture
def emu(emulator_bin: str, tmp_path: Any) -> Iterator[Emu]:
    e = Emu(str(tmp_path / "rover")).start()
    yield e
    e.stop()


@pytest.fixture
def faultlink(emu: Emu, tmp_path: Any) -> Iterator[Callable[..., FaultLink]]:
    """Factory: ``faultlink(seed=..., both=Faults(...))`` starts a proxy in front of the emulator."""
    made: List[FaultLink] = []

    def make(**kw: Any) -> FaultLink:
        fl = FaultLink(emu.link, str(tmp_path / f"faulty{len(made)}"), **kw)
        fl.start()
        made.append(fl)
        return fl

    yield make
    for fl in made:
        fl.stop()


# ------------------------------------------------------------------------- resource snapshots

def fd_count() -> int:
    return len(os.listdir("/proc/self/fd"))


def tty_fds() -> int:
    """Open file descriptors on ttys/ptys (the hub's serial ports), ignoring pipes to child processes."""
    n = 0
    for fd in os.listdir("/proc/self/fd"):
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        n += target.startswith(("/dev/pts/", "/dev/tty", "/dev/ptmx"))
    return n


def hubwire_threads() -> List[str]:
    return sorted(t.name for t in threading.enumerate() if t.name.startswith("hubwire"))


def hubwire_thread_ids() -> Set[int]:
    """Identities of the live hubwire threads: compared with an earlier snapshot, the ones a test
    added (and leaked), not disturbed by another test's thread that ends meanwhile."""
    return {t.ident for t in threading.enumerate() if t.name.startswith("hubwire") and t.ident is not None}


def settle(predicate: Callable[[], bool], timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > end:
            return False
        time.sleep(0.02)
    return True


def wait_until(predicate: Callable[[], bool], timeout: float = 5.0, what: str = "condition") -> None:
    if not settle(predicate, timeout):
        raise AssertionError(f"timed out after {timeout} s waiting for {what}")


# --------------------------------------------------------------------------- hostile device

GOOD_DESCRIPTOR = (b'{"p":1,"n":"hostile","ch":[{"id":1,"n":"x","a":"rw","t":"u16","min":0,"max":1000},'
                   b'{"id":2,"n":"ev","a":"e","t":"u8"},{"id":3,"n":"s","a":"rs","t":"u16"}]}')


class HostileDevice:
    """A scripted device on a pty (the hub opens ``path``). It handshakes and serves its descriptor
    like a real one, unless told otherwise:

    - ``descriptor``: the bytes served; ``announce_length`` / ``announce_hash`` override the hello;
    - ``answer_hello=False``: never answers (a device that is not there, or a mute one);
    - ``answer_chunks=False``: handshakes but never serves the descriptor;
    - ``on_request(frame) -> bytes | None``: wire bytes to send for an ``R``/``C`` (None: a normal ACK / u16 0);
    - :meth:`send` writes arbitrary bytes; :meth:`flood` writes a generator's bytes as fast as the
      hub reads them, for a while.
    """

    def __init__(self, descriptor: bytes = GOOD_DESCRIPTOR, *, answer_hello: bool = True, answer_chunks: bool = True,
                 announce_length: Optional[int] = None, announce_hash: Optional[int] = None,
                 max_payload: int = 32, on_request: Optional[Callable[[Any], Optional[bytes]]] = None) -> None:
        self.descriptor = descriptor
        self.answer_hello = answer_hello
        self.answer_chunks = answer_chunks
        self.length = len(descriptor) if announce_length is None else announce_length
        self.hash = m.fnv1a32(descriptor) if announce_hash is None else announce_hash
        self.max_payload = max_payload
        self.on_request = on_request
        self.nonce = 0x0BADCAFE
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self.slave)
        self.received: List[Any] = []
        self.chunk_requests = 0
        self._wlock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="hostile-device", daemon=True)

    def __enter__(self) -> "HostileDevice":
        self._thread.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self._stop.set()
        self._thread.join(5)
        os.close(self.master)
        os.close(self.slave)

    def send(self, data: bytes, deadline: float = 5.0) -> None:
        end = time.monotonic() + deadline
        with self._wlock:
            view = memoryview(data)
            while view and time.monotonic() < end:
                try:
                    n = os.write(self.master, view)
                    view = view[n:]
                except BlockingIOError:
                    select.select([], [self.master], [], 0.05)

    def frame(self, t: int, seq: int, cid: int, payload: bytes = b"") -> None:
        self.send(encode_frame(t, seq, cid, payload))

    def flood(self, chunks: Iterator[bytes], seconds: float, min_bytes: int = 0, max_seconds: float = 0.0) -> int:
        """Write chunks for ``seconds`` (blocking while the hub does not read), and on until
        ``min_bytes`` were written or ``max_seconds`` passed (a slow, busy machine); returns bytes written."""
        start = time.monotonic()
        end, hard = start + seconds, start + max(seconds, max_seconds)
        total = 0
        for c in chunks:
            now = time.monotonic()
            if now >= hard or (now >= end and total >= min_bytes):
                break
            self.send(c, deadline=max(0.0, hard - now))
            total += len(c)
        return total

    def hello(self, reply: bool) -> None:
        h = m.Hello(1, m.FLAG_DEVICE | (m.FLAG_REPLY if reply else 0), self.nonce, self.max_payload, 250,
                    self.hash, self.length & 0xFFFF)
        self.frame(m.HELLO, 0, 0, h.pack())

    def _run(self) -> None:
        dec = FrameDecoder(255)
        last_beat = 0.0
        linked = False
        while not self._stop.is_set():
            r, _, _ = select.select([self.master], [], [], 0.02)
            now = time.monotonic()
            if linked and now - last_beat > 0.2:
                last_beat = now
                self.frame(m.HEARTBEAT, 0, 0, m.Heartbeat(1, 250, 0, 0, 0).pack())
            if not r:
                continue
            try:
                data = os.read(self.master, 4096)
            except (BlockingIOError, OSError):
                continue
            for f in dec.feed(data):
                self.received.append(f)
                if f.type == m.HELLO and self.answer_hello:
                    if not m.Hello.unpack(f.payload).is_reply:
                        self.hello(True)
                    linked = True
                elif f.type == m.CHUNK and self.answer_chunks:
                    self.chunk_requests += 1
                    req = m.ChunkRequest.unpack(f.payload)
                    n = min(req.want, self.max_payload - 4)
                    data_ = self.descriptor[req.offset:req.offset + n]
                    self.frame(m.CHUNK, f.seq, 0, m.Chunk(req.offset, self.length & 0xFFFF, data_).pack())
                elif f.type in (m.REQUEST, m.CONTROL, m.SUBSCRIBE):
                    out = self.on_request(f) if self.on_request else None
                    if out is not None:
                        self.send(out)
                    elif f.type == m.REQUEST:
                        self.frame(m.RESPONSE, f.seq, f.id, b"\x00\x00")
                    elif f.type == m.SUBSCRIBE:
                        self.frame(m.ACK, f.seq, f.id, f.payload[:2])
                    else:
                        self.frame(m.ACK, f.seq, f.id)
