"""Reading a large value in windows (PROTOCOL.md 12.8).

A value longer than one frame comes back as fragments, all of one try or nothing (12.4): on a lossy
line its chance falls with its length. So the hub reads such a value whole once, and when that try
gets no answer it asks for the value in windows, ``R`` [u16 offset, u16 count], each answered by
one ``r`` [u16 offset, u16 total, u32 FNV-1a of the whole value, bytes], each an ordinary
idempotent read retried on its own: the read then costs tries in proportion to the value's length.

No torn value: every window carries the hash of the whole value as it was when that window was
taken. The windows kept all carry the same (total, hash); a window with another one means the value
changed, and the assembly starts over from that window's snapshot. The assembled value is handed
on only when its own hash is the one its windows carry.

:class:`ReadPlan` decides what to ask next and keeps the assembly (no I/O); :func:`read_async` and
:func:`read_sync` drive it through the session's transactions.
"""
from __future__ import annotations

import struct
import time
from typing import Any, Optional

from ..descriptor import Channel
from ..errors import HubwireError, NakError, Timeout
from ..wire import messages as m
from ..wire.frame import Frame
from ..wire.messages import NakCode

__all__ = ["WINDOW_HEADER", "window_request", "WindowAssembly", "ReadPlan", "read_async", "read_sync"]

#: offset (u16), total (u16), FNV-1a 32 of the whole value (u32), before a window's bytes
WINDOW_HEADER = 8
_HEADER = struct.Struct("<HHI")


def window_request(offset: int, count: int) -> bytes:
    """The payload of an ``R`` asking for ``count`` bytes of a value's wire form from ``offset``."""
    return struct.pack("<HH", offset, count)


class WindowAssembly:
    """The windows of one snapshot of a value, put together; ``restarts`` counts snapshots dropped."""

    def __init__(self) -> None:
        self.total: Optional[int] = None
        self.hash = 0
        self._buf = bytearray()
        self._have = bytearray()  # 1 for each byte in hand
        self.restarts = 0

    def next_offset(self) -> int:
        """The first byte not in hand (0 before any window)."""
        at = self._have.find(0) if self.total is not None else 0
        return 0 if at < 0 else at

    def _start(self, total: int, hash: int) -> None:
        if self.total is not None:
            self.restarts += 1
        self.total, self.hash = total, hash
        self._buf, self._have = bytearray(total), bytearray(total)

    def add(self, asked: int, payload: bytes) -> Optional[bytes]:
        """Take the answer to a window asked at ``asked``; the whole value once every byte is in hand
        and its hash checks, else None. HubwireError for an answer that is not such a window."""
        if len(payload) < WINDOW_HEADER:
            raise HubwireError(f"a window answer of {len(payload)} bytes is shorter than its header")
        offset, total, hash = _HEADER.unpack_from(payload)
        data = payload[WINDOW_HEADER:]
        if offset != asked or offset + len(data) > total or (not data and offset < total):
            raise HubwireError(f"a window answer for offset {offset} ({len(data)} of {total} bytes) "
                               f"does not fit the request for offset {asked}")
        if (total, hash) != (self.total, self.hash):  # another snapshot: start over from this one
            self._start(total, hash)
        self._buf[offset:offset + len(data)] = data
        self._have[offset:offset + len(data)] = b"\x01" * len(data)
        if self._have.find(0) >= 0:
            return None
        whole = bytes(self._buf)
        if m.fnv1a32(whole) == self.hash:
            return whole
        self.total = None  # windows of snapshots that share a hash: none of them is kept
        self._start(total, hash)
        return None


class ReadPlan:
    """One read of ``ch``: what to send next (:meth:`request`) and what came of it (:meth:`answered`,
    :meth:`failed`); ``value`` is the whole payload once read.

    A value that fits one frame, or one a device that predates windows holds, is read whole as
    always. A larger one is read whole with one try (no loss costs nothing more), then in windows,
    each retried within the session's tries and asked again after a Timeout until the read's
    deadline: ``timeout`` (or the session's retry timeout times its tries) per window."""

    def __init__(self, core: Any, ch: Channel, timeout: Optional[float], what: str) -> None:
        self.core, self.ch, self.timeout, self.what = core, ch, timeout, what
        self.limit = core.link.peer_limit()
        large = ch.codec.max_size > self.limit
        self.windows = large and core.whole_reads_only != (core.descriptor_nonce,)
        self.tries: Optional[int] = 1 if self.windows else None
        self.asm: Optional[WindowAssembly] = None
        self.asked = 0
        self.deadline = 0.0
        self.value: Optional[bytes] = None

    def request(self) -> Optional[bytes]:
        """The payload of the next ``R`` (``tries`` for it), None once the value is in hand."""
        if self.value is not None:
            return None
        if self.asm is None:
            return b""
        self.asked = self.asm.next_offset()
        return window_request(self.asked, self.limit - WINDOW_HEADER)

    def answered(self, a: Frame) -> None:
        if a.type != m.RESPONSE:
            raise HubwireError(f"unexpected answer type 0x{a.type:02x} to a read of {self.what or self.ch.id}")
        if self.asm is None:
            self.value = a.payload
        else:
            self.value = self.asm.add(self.asked, a.payload)
            self.tries = None
            if self.value is None and time.monotonic() > self.deadline:
                # answers keep coming but no whole value checks (a value that never holds still, or
                # a device whose windows do not match their hash): the read ends by its deadline too
                raise Timeout(f"no whole value of {self.what or self.ch.id} on {self.core.url} by its "
                              f"deadline ({self.asm.restarts} changes of the value seen)")

    def failed(self, e: BaseException) -> None:
        """A transaction ended without an answer: raises ``e`` unless the read goes on."""
        core = self.core
        if self.asm is None:
            if not (self.windows and isinstance(e, Timeout)):
                raise e
            # the whole value did not come in one try: windows, each within the session's tries
            self.asm, self.tries = WindowAssembly(), None
            per = self.timeout if self.timeout is not None else core.retry_timeout * core.tries
            windows = -(-self.ch.codec.max_size // (self.limit - WINDOW_HEADER))
            self.deadline = time.monotonic() + per * windows
            return
        if isinstance(e, NakError) and e.code == NakCode.BAD_LENGTH and self.asm.total is None:
            # a device that predates windows: whole reads from now on, for this boot of the device
            core.whole_reads_only = (core.descriptor_nonce,)
            self.asm, self.windows = None, False
            return
        if isinstance(e, NakError) and e.code == NakCode.BAD_OFFSET and self.asm.total is not None:
            restarts = self.asm.restarts + 1  # the value (a list, a string) got shorter: start over
            self.asm = WindowAssembly()
            self.asm.restarts = restarts
        elif not isinstance(e, Timeout):
            raise e
        if time.monotonic() > self.deadline:
            raise Timeout(f"no whole value of {self.what or self.ch.id} on {core.url} by its deadline "
                          f"({self.asm.restarts} changes of the value seen)") from e


async def read_async(core: Any, ch: Channel, timeout: Optional[float], what: str) -> bytes:
    """Read ``ch``'s value (wire form) on the session's loop."""
    plan = ReadPlan(core, ch, timeout, what)
    while (payload := plan.request()) is not None:
        try:
            a = await core.tx.transact(m.REQUEST, ch.id, payload, timeout=timeout, what=what, tries=plan.tries)
        except (Timeout, NakError) as e:
            plan.failed(e)
        else:
            plan.answered(a)
    assert plan.value is not None
    return plan.value


def read_sync(session: Any, ch: Channel, timeout: Optional[float], what: str) -> bytes:
    """Read ``ch``'s value (wire form) from this thread (:class:`hubwire.session.Session`)."""
    plan = ReadPlan(session.core, ch, timeout, what)
    while (payload := plan.request()) is not None:
        try:
            a = session.transact(m.REQUEST, ch.id, payload, timeout=timeout, what=what, tries=plan.tries)
        except (Timeout, NakError) as e:
            plan.failed(e)
        else:
            plan.answered(a)
    assert plan.value is not None
    return plan.value
