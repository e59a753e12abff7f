"""Discovery (PROTOCOL.md §3.3): the device's descriptor, from memory, from the on-disk cache, or
downloaded with ``J`` chunk requests, several in flight, lost chunks asked again."""
from __future__ import annotations

import asyncio
import time
from collections import deque
from typing import Any, Deque, Dict, Optional

from ..descriptor.cache import DescriptorCache, descriptor_digest
from ..descriptor import MAX_DESCRIPTOR_SIZE, Descriptor, parse_descriptor
from ..errors import DescriptorError, HubwireError, LinkLost, NakError, Timeout
from ..wire import messages as m
from ..wire.messages import NakCode
from .link import HUB_MAX_PAYLOAD
from .transactions import Pending

__all__ = ["Discovery", "CHUNK_WINDOW"]

#: chunk requests in flight at once
CHUNK_WINDOW = 4
#: downloads of a descriptor whose hash does not match before giving up
DOWNLOAD_ATTEMPTS = 3


class Discovery:
    """Loads descriptors for one session. ``core`` provides ``tx`` (Transactions), ``link``, ``stats``,
    ``retry_timeout``, ``connect_timeout``, ``descriptor``, ``closed``, ``report_progress(n, total)``
    and ``progress_at`` (the time of the last progress, which it updates)."""

    def __init__(self, core: Any, cache: DescriptorCache) -> None:
        self.core = core
        self.cache = cache

    async def load(self, hello: m.Hello) -> Descriptor:
        """The descriptor ``hello`` announces (DescriptorError, Timeout, LinkLost, NakError)."""
        if hello.descriptor_length > MAX_DESCRIPTOR_SIZE:
            raise DescriptorError(
                f"descriptor: the device announces {hello.descriptor_length} bytes, more than the hub's "
                f"limit of {MAX_DESCRIPTOR_SIZE} bytes (not downloaded)")
        stats = self.core.stats
        digest = hello.digest
        # Reuse only what the device's SHA-256 digest vouches for: a device that announces none
        # (an older library) is always downloaded, never cached (PROTOCOL.md 7.1).
        cur: Optional[Descriptor] = self.core.descriptor
        if digest is not None and cur is not None and descriptor_digest(cur.raw) == digest:
            stats.cache_hits += 1
            return cur
        cached = self.cache.get(digest, hello.descriptor_length) if digest is not None else None
        if cached is not None:
            try:
                d = parse_descriptor(cached)
                stats.cache_hits += 1
                return d
            except DescriptorError:
                pass
        last: Optional[BaseException] = None
        for _ in range(DOWNLOAD_ATTEMPTS):
            raw = await self.download(hello)
            last = _mismatch(hello, raw)
            if last is not None:
                continue
            d = parse_descriptor(raw)
            if digest is not None:
                self.cache.put(digest, raw)
            return d
        assert last is not None
        raise last

    async def download(self, hello: m.Hello) -> bytes:
        """Fetch the descriptor bytes with a window of chunk requests."""
        total = hello.descriptor_length
        self.core.stats.downloads += 1
        if total == 0:
            return b""
        want = max(1, min(255, HUB_MAX_PAYLOAD - 4, hello.max_payload - 4))
        # no gate: discovery runs only while the session is not READY, when no other transaction runs
        job = _Download(self.core, total, want)
        try:
            return await job.run()
        finally:
            job.forget()


def _mismatch(hello: m.Hello, raw: bytes) -> Optional[DescriptorError]:
    """Why downloaded bytes are not the descriptor ``hello`` announced, or None."""
    h = m.fnv1a32(raw)
    if h != hello.descriptor_hash:
        return DescriptorError(f"descriptor hash mismatch: device announced {hello.descriptor_hash:08x}, "
                               f"downloaded {len(raw)} bytes hash to {h:08x}")
    if hello.digest is not None and descriptor_digest(raw) != hello.digest:
        return DescriptorError(f"descriptor digest mismatch: device announced {hello.digest.hex()}, "
                               f"downloaded {len(raw)} bytes have SHA-256 {descriptor_digest(raw).hex()}...")
    return None


class _Download:
    """One download in progress: a window of requests, the bytes received, the holes left."""

    def __init__(self, core: Any, total: int, want: int) -> None:
        self.core = core
        self.total = total
        self.want = want
        self.buf = bytearray(total)
        self.have = bytearray(total)  # 1 where received
        self.received = 0
        self.inflight: Dict[int, Pending] = {}  # offset -> pending
        self.next_off = 0
        self.gaps: Deque[int] = deque()

    def forget(self) -> None:
        for p in self.inflight.values():
            self.core.tx.unregister(p)

    async def run(self) -> bytes:
        core = self.core
        while self.received < self.total:
            if core.closed:
                raise HubwireError("session closed")
            if not core.link.linked:
                raise LinkLost("link lost during descriptor download")
            self._fill_window()
            before = self.received
            await self._wait_any()
            self._harvest(time.monotonic())
            if self.received != before:
                core.report_progress(self.received, self.total)
            if self.received < self.total and not self.inflight and not self.gaps and self.next_off >= self.total:
                self.gaps.append(self.have.index(0))  # holes left by short answers
        return bytes(self.buf)

    def _fill_window(self) -> None:
        tx = self.core.tx
        while len(self.inflight) < CHUNK_WINDOW and (self.gaps or self.next_off < self.total):
            if self.gaps:
                off = self.gaps.popleft()
            else:
                off = self.next_off
                self.next_off += self.want
            if off in self.inflight or self.have[off]:
                continue
            p = tx.register(m.CHUNK, 0, m.ChunkRequest(off, self.want).pack())
            self.inflight[off] = p
            self.core.stats.chunk_requests += 1
            tx.transmit(p)

    async def _wait_any(self) -> None:
        if not self.inflight:
            return
        retry = self.core.retry_timeout
        now = time.monotonic()
        left = min(p.sent_at + retry - now for p in self.inflight.values())
        futs = [p.fut for p in self.inflight.values() if p.fut is not None]  # coroutine waiters: always set
        if left > 0 and not any(f.done() for f in futs):
            await asyncio.wait(futs, timeout=left, return_when=asyncio.FIRST_COMPLETED)

    def _harvest(self, now: float) -> None:
        core = self.core
        for off, p in list(self.inflight.items()):
            fut = p.fut
            assert fut is not None  # registered for a coroutine
            if not fut.done():
                if now - p.sent_at >= core.retry_timeout:
                    # Chunk requests are idempotent: on a lossy line keep asking for as long as
                    # the download as a whole makes progress (connect_timeout).
                    if now - core.progress_at >= core.connect_timeout:
                        raise Timeout(f"descriptor chunk at offset {off} not answered after "
                                      f"{p.tries} tries: no progress for {core.connect_timeout:g} s")
                    core.tx.retry(p)
                continue
            a = fut.result()  # raises LinkLost and the like
            if a.type == m.NAK and a.payload[:1] == bytes((NakCode.NOT_LINKED,)):
                # the device re-links on the hello this NAK triggered: ask again when the retry
                # timer fires (counts as a try)
                p.rearm()
                continue
            del self.inflight[off]
            core.tx.unregister(p)
            self._take(off, a)

    def _take(self, off: int, a: Any) -> None:
        if a.type == m.NAK:
            code = a.payload[0] if a.payload else 0
            raise NakError(code, None, f"descriptor chunk at offset {off}")
        try:
            c = m.Chunk.unpack(a.payload)
        except m.PayloadError as e:
            raise DescriptorError(f"malformed descriptor chunk: {e}") from None
        total = self.total
        if c.total != total:
            raise DescriptorError(f"descriptor length changed: hello said {total}, chunk says {c.total}")
        if c.offset != off:
            raise DescriptorError(f"descriptor chunk asked for offset {off} answers offset {c.offset}")
        if off + len(c.data) > total:
            raise DescriptorError(f"descriptor chunk at offset {off} with {len(c.data)} bytes runs past "
                                  f"the end of the {total}-byte descriptor")
        if not c.data:
            raise DescriptorError(f"empty descriptor chunk at offset {off} of {total}")
        for i, b in enumerate(c.data):
            if not self.have[off + i]:
                self.have[off + i] = 1
                self.buf[off + i] = b
                self.received += 1
        self.core.progress_at = time.monotonic()
        end = off + len(c.data)
        if end < total and not self.have[end] and end not in self.inflight and len(c.data) < self.want:
            self.gaps.append(end)  # shorter answer than asked: fetch the rest
