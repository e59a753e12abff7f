"""The hub's answers to the device's own transactions (PROTOCOL.md §10): ``R`` (read a hub value),
``C`` (write one, or call a hub action) and ``J`` (a chunk of the hub's descriptor).

Answered only once the device's descriptor is loaded (its ``"hub"`` list maps hub ids to names);
before that the device's retries are the flow control. A device ``C`` with the seq and id of the
last device transaction is a duplicate: its remembered answer is sent again and the handler does
not run twice (the memory is reset by a new device nonce). The answer to a transaction the device
has given up on (it sent a newer one while the handler ran) is dropped, never sent late. Handlers run where the application's
callbacks run (the dispatcher thread, or the caller's loop for ``hubwire.aio``; a coroutine is
awaited there); the answer goes out when they return.
"""
from __future__ import annotations

import asyncio
import logging
from typing import Any, Callable, Optional, Tuple

from ..descriptor import Channel
from ..errors import InvalidValue
from ..hub import HubChannel, HubChannels, bind_status
from ..text import clip
from ..wire import messages as m
from ..wire.frame import Frame
from ..wire.messages import NakCode
from .runner import run_handler

__all__ = ["HubAnswers"]

log = logging.getLogger("hubwire")


class HubAnswers:
    """Answers one session's device transactions from ``channels``; ``core`` provides ``loop``,
    ``link``, ``stats``, ``dispatch`` and ``decodable()``."""

    def __init__(self, core: Any, channels: HubChannels) -> None:
        self.core = core
        self.loop: asyncio.AbstractEventLoop = core.loop
        self.channels = channels
        self._device_nonce: Optional[int] = None
        self._last: Optional[Tuple[int, int, int]] = None  # type, seq, id
        self._last_answer: Optional[Tuple[int, bytes]] = None  # None while its handler runs
        self._epoch = 0

    def on_device_frame(self, f: Frame) -> None:
        """A device ``R``, ``C`` or ``J`` (request)."""
        core = self.core
        desc = core.decodable()
        if desc is None or not core.link.linked:
            core.stats.device_unanswered += 1
            return  # not answered: the device retries
        nonce = core.link.device_hello.nonce
        if nonce != self._device_nonce:
            self._device_nonce, self._last, self._last_answer = nonce, None, None
            self._epoch += 1
        key = (f.type, f.seq, f.id)
        if f.type == m.CONTROL and key == self._last:
            core.stats.device_duplicates += 1
            if self._last_answer is not None:  # else its handler still runs: answered when it returns
                core.link.send_frame(self._last_answer[0], f.seq, f.id, self._last_answer[1])
            return
        self._last, self._last_answer = key, None
        if f.type == m.CHUNK:
            self._chunk(f)
            return
        exp = next((c for c in desc.hub if c.id == f.id), None)
        hc = None if exp is None else self.channels.get(exp.name)
        if exp is None or hc is None:
            self._reply(f, m.NAK, bytes((NakCode.UNKNOWN_CHANNEL,)))
        elif f.type == m.REQUEST:
            core.stats.device_reads += 1
            self._read(f, exp, hc)
        elif "w" in exp.access:
            core.stats.device_writes += 1
            self._write(f, exp, hc)
        else:
            core.stats.device_calls += 1
            self._call(f, exp, hc)

    def _reply(self, f: Frame, type: int, payload: bytes = b"", epoch: Optional[int] = None) -> None:
        if epoch is not None and epoch != self._epoch:
            return  # the device rebooted while the handler ran
        if epoch is not None and self._last != (f.type, f.seq, f.id):
            # the device sent a newer R, C or J while the handler ran: it gave up on this one (one
            # at a time, PROTOCOL.md 10.2), and a late answer could meet a newer one of its seq and id
            self.core.stats.device_answers_dropped += 1
            return
        if type == m.NAK:
            self.core.stats.device_refused += 1
        if self._last == (f.type, f.seq, f.id):
            self._last_answer = (type, payload)
        self.core.link.send_frame(type, f.seq, f.id, payload)

    def _chunk(self, f: Frame) -> None:
        req = m.ChunkRequest.unpack(f.payload)
        raw = self.channels.descriptor()
        if req.offset > len(raw):
            self._reply(f, m.NAK, bytes((NakCode.BAD_OFFSET,)))
            return
        room = max(0, self.core.link.device_hello.max_payload - 4)
        data = raw[req.offset:req.offset + min(req.want, room)]
        self._reply(f, m.CHUNK, m.Chunk(req.offset, len(raw), data).pack())

    def _read(self, f: Frame, exp: Channel, hc: HubChannel) -> None:
        if "r" not in exp.access or not hc.readable:
            self._reply(f, m.NAK, bytes((NakCode.NOT_READABLE,)))
        elif bind_status(exp, hc):
            self._reply(f, m.NAK, bytes((bind_status(exp, hc),)))
        elif hc.getter is None:
            self._answer_value(f, hc, hc.channel.codec, hc.value, self._epoch)
        else:
            self._run(f, hc.getter, (), lambda v, e: self._answer_value(f, hc, hc.channel.codec, v, e))

    def _write(self, f: Frame, exp: Channel, hc: HubChannel) -> None:
        value = self._argument(f, exp, hc, hc.writable)
        if value is _REFUSED:
            return
        if hc.on_write is None:
            hc.store(value)
            self._reply(f, m.ACK)
            return

        def done(result: Any, epoch: int) -> None:
            if result is False:
                self._reply(f, m.NAK, bytes((NakCode.REJECTED,)), epoch)
            else:
                hc.store(value)
                self._reply(f, m.ACK, b"", epoch)
        self._run(f, hc.on_write, (value,), done)

    def _call(self, f: Frame, exp: Channel, hc: HubChannel) -> None:
        arg = self._argument(f, exp, hc, hc.callable)
        if arg is _REFUSED:
            return
        returns = hc.channel.returns
        assert hc.fn is not None and returns is not None
        args = () if hc.channel.codec.kind == "void" else (arg,)

        def done(result: Any, epoch: int) -> None:
            if result is False and returns.type_obj.get("t") != "bool":  # refused, as a write handler may
                self._reply(f, m.NAK, bytes((NakCode.REJECTED,)), epoch)
            else:
                self._answer_value(f, hc, returns, result, epoch, ack_void=True)
        self._run(f, hc.fn, args, done)

    def _argument(self, f: Frame, exp: Channel, hc: HubChannel, allowed: bool) -> Any:
        """The checked value of a device C (PROTOCOL.md §5 order), or _REFUSED after a NAK."""
        code = NakCode.NOT_WRITABLE if not allowed or not ("w" in exp.access or "c" in exp.access) else bind_status(exp, hc)
        if code:
            self._reply(f, m.NAK, bytes((code,)))
            return _REFUSED
        try:
            return hc.channel.check(hc.channel.codec.decode(f.payload))
        except InvalidValue as e:
            self._reply(f, m.NAK, bytes((e.code,)))
            return _REFUSED

    def _answer_value(self, f: Frame, hc: HubChannel, codec: Any, value: Any, epoch: int, ack_void: bool = False) -> None:
        if ack_void and codec.kind == "void":
            self._reply(f, m.ACK, b"", epoch)
            return
        try:
            payload = codec.encode(value)
        except InvalidValue as e:
            log.warning("hubwire: hub channel %s gave %s: %s", clip(hc.name), clip(repr(value), 60), clip(str(e), 120))
            self._reply(f, m.NAK, bytes((NakCode.REJECTED,)), epoch)
            return
        h = self.core.link.device_hello
        if h is not None and len(payload) > h.max_payload:
            self._reply(f, m.NAK, bytes((NakCode.BAD_LENGTH,)), epoch)
            return
        self._reply(f, m.RESPONSE, payload, epoch)

    def _run(self, f: Frame, fn: Callable[..., Any], args: Tuple[Any, ...], done: Callable[[Any, int], None]) -> None:
        """Run an application handler where callbacks run; ``done(result, epoch)`` on the loop, or
        NAK REJECTED when it raises."""
        epoch, loop = self._epoch, self.loop

        def finish(ok: bool, result: Any) -> None:
            if ok:
                done(result, epoch)
            else:
                log.warning("hubwire: hub channel handler %r raised: %s", fn, clip(repr(result), 160))
                self._reply(f, m.NAK, bytes((NakCode.REJECTED,)), epoch)

        run_handler(loop, self.core.dispatch, fn, args, finish)


_REFUSED = object()
