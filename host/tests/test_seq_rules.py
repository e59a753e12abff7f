"""The hub's seq rules (PROTOCOL.md 4.1, 4.4, 10.3) and the bound on transactions in flight, on the
real :class:`Transactions` with a scripted link and a model of the device's duplicate memories:

- a new ``C`` never carries the (seq, id) of the control the device remembers;
- a new hub event never carries the (seq, id) of the event the device remembers;
- no (seq, id) is ever in flight twice, and every answer reaches the message it answers;
- beyond ``max_in_flight`` callers wait asleep and get their turn in order.
"""
from __future__ import annotations

import asyncio
import threading
import time
from types import SimpleNamespace
from typing import Any, Dict, List, Optional, Tuple

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hubwire.errors import LinkLost
from hubwire.session.fragments import Reassembler
from hubwire.session.records import Stats
from hubwire.session.seqs import SeqRules
from hubwire.session.transactions import Transactions
from hubwire.wire import messages as m
from hubwire.wire.frame import Frame

_ANSWER = {m.REQUEST: m.RESPONSE, m.CHUNK: m.CHUNK, m.SUBSCRIBE: m.ACK}


class FakeLink:
    def __init__(self) -> None:
        self.out: List[bytes] = []
        self.reassembler = Reassembler(SimpleNamespace(dropped=0))
        self.pacer = SimpleNamespace(burst_time=lambda wire: 0.0)

    def encode(self, type: int, seq: int, id: int, payload: bytes = b"") -> bytes:
        return bytes((type, seq, id))

    def send(self, data: bytes) -> None:
        self.out.append(data)


def make_tx(limit: int = 64, loop: Optional[asyncio.AbstractEventLoop] = None) -> Transactions:
    core = SimpleNamespace(loop=loop or asyncio.new_event_loop(), link=FakeLink(), stats=Stats(), max_in_flight=limit,
                           hub=SimpleNamespace(kick=lambda: None), wake=lambda: None, closed=False, url="fake",
                           tries=5)
    return Transactions(core)


class Msg:
    def __init__(self, kind: int, id: int, hub_side: bool = False) -> None:
        self.kind, self.id, self.hub_side = kind, id, hub_side
        self.key: Tuple[int, int] = (-1, id)
        self.p: Any = None
        self.taken = False  # applied (a C) or delivered (an event) by the device
        self.answer: Optional[Frame] = None


class Model:
    """The device's memories (session.cpp handle(), hub_link.cpp hubEvent()) and the line between."""

    def __init__(self, tx: Transactions) -> None:
        self.tx = tx
        self.last_txn: Optional[Tuple[bool, int, int]] = None
        self.last_answer = m.ACK
        self.event_mem: Optional[Tuple[int, int]] = None
        #: to the hub, in order (None: the device's hello answering a hub hello)
        self.answers: List[Optional[Tuple[Frame, Msg]]] = []
        self.live: List[Msg] = []
        self.control: Optional[Msg] = None
        self.event: Optional[Msg] = None

    def drawn(self, msg: Msg) -> None:
        seq, id = msg.key
        keys = [x.key for x in self.live]
        assert len(keys) == len(set(keys)), f"a (seq, id) in flight twice: {sorted(keys)}"
        if msg.kind == m.CONTROL:
            assert self.last_txn != (True, seq, id), f"new control {msg.key} is the one the device remembers"
        if msg.kind == m.EVENT:
            assert self.event_mem != (seq, id), f"new event {msg.key} is the one the device remembers"

    def receive(self, msg: Msg, reply_nak: bool) -> None:
        seq, id = msg.key
        if msg.kind == m.EVENT:
            if self.event_mem == (seq, id):
                assert msg.taken, f"a new event {msg.key} taken for a retry: never delivered"
            else:
                msg.taken, self.event_mem = True, (seq, id)
            self.answers.append((Frame(m.ACK, seq, id, b""), msg))
            return
        control = msg.kind == m.CONTROL
        if control and self.last_txn == (True, seq, id):
            assert msg.taken, f"a new control {msg.key} taken for a retry: never applied"
            t = self.last_answer
        else:
            self.last_txn = (control, seq, id)
            if control:
                msg.taken = True
                t = self.last_answer = m.NAK if reply_nak else m.ACK
            else:
                t = _ANSWER[msg.kind]
        self.answers.append((Frame(t, seq, id, b"\x0d" if t == m.NAK else b""), msg))

    def deliver(self, lost: bool) -> None:
        answer = self.answers.pop(0)
        if lost:
            return
        if answer is None:
            self.tx.hello_answered()
            return
        f, msg = answer
        key = (f.seq, f.id)
        for hub in (self.control, self.event):
            if hub is not None and hub.hub_side and hub.key == key and f.type in (m.ACK, m.NAK):
                assert hub is msg, "an answer reached the wrong hub message"
                hub.answer = f
                return
        p = self.tx.pending.get(key)
        if p is not None and not p.done():
            assert p is msg.p, f"an answer to {msg.key} reached another transaction"
        if self.tx.on_answer(f):
            msg.answer = f


ACTIONS = ["read", "retry_read", "end_read", "control", "retry_control", "end_control",
           "event", "retry_event", "deliver", "hello", "reboot"] + ["control", "end_control", "burst"] * 3
#: a burst of exactly 255 or 254 round trips brings the seq round to the one before it
BURST = st.one_of(st.just(255), st.just(254), st.integers(1, 255))


def seqs_all_taken(tx: Transactions, id: int, type: int = m.REQUEST) -> bool:
    """No seq is free for a ``type`` to ``id``: each is in flight, held, its answer may still come,
    or (an event) the device may remember it."""
    rules = tx.rules
    return all((s, id) in tx.pending or (s, id) in tx.held or (s, id) in rules.unanswered
               or (type == m.EVENT and s in rules.events) for s in range(256))


# Answers come in order but as late as the draws say: a late one may wait while the counter comes
# round many times. Fixed examples in CI; `make soak` style longer searches: raise max_examples.
@settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_new_messages_never_carry_what_the_device_remembers(data: Any) -> None:
    tx = make_tx(limit=8)
    model = Model(tx)
    reads: List[Msg] = []

    def send(msg: Msg) -> None:
        if data.draw(st.booleans(), label="reaches the device"):
            model.receive(msg, data.draw(st.booleans(), label="refused") if msg.kind == m.CONTROL else False)
        tx.core.link.out.clear()

    for _ in range(data.draw(st.integers(20, 400), label="steps")):
        action = data.draw(st.sampled_from(ACTIONS), label="action")
        if action == "read":
            kind = data.draw(st.sampled_from([m.REQUEST, m.CHUNK, m.SUBSCRIBE]))
            msg = Msg(kind, 0 if kind == m.CHUNK else data.draw(st.integers(0, 3)))
            msg.p = tx.try_register(kind, msg.id, b"", threaded=True, slot=True)
            if msg.p is None:
                assert len(tx.pending) >= 8 or seqs_all_taken(tx, msg.id)
                continue
            msg.key = (msg.p.seq, msg.id)
            model.live.append(msg)
            reads.append(msg)
            model.drawn(msg)
            tx.transmit(msg.p)
            send(msg)
        elif action == "retry_read" and reads:
            msg = data.draw(st.sampled_from(reads))
            tx.retry(msg.p)
            msg.key = (msg.p.seq, msg.id)
            model.drawn(msg)
            send(msg)
        elif action == "end_read" and reads:
            msg = data.draw(st.sampled_from(reads))
            tx.unregister(msg.p)
            reads.remove(msg)
            model.live.remove(msg)
        elif action == "control" and model.control is None:
            bind = data.draw(st.booleans(), label="bind report")
            msg = Msg(m.CONTROL, 0 if bind else data.draw(st.integers(0, 1)), hub_side=bind)
            if bind:
                seq = tx.hold(m.CONTROL, 0)
            else:
                msg.p = tx.try_register(m.CONTROL, msg.id, b"", threaded=True, slot=True)
                seq = None if msg.p is None else msg.p.seq
            if seq is None:
                continue
            msg.key = (seq, msg.id)
            model.live.append(msg)
            model.control = msg
            model.drawn(msg)
            send(msg)
        elif action == "retry_control" and model.control is not None and model.control.answer is None:
            send(model.control)  # the hub sends a control again only while it has no answer
        elif action == "end_control" and model.control is not None:
            msg, model.control = model.control, None
            model.live.remove(msg)
            if msg.hub_side:
                tx.let_go(msg.key[0], 0, msg.answer)
            else:
                tx.unregister(msg.p)
        elif action == "event" and model.event is None:
            msg = Msg(m.EVENT, data.draw(st.integers(1, 2)), hub_side=True)
            seq = tx.hold(m.EVENT, msg.id)
            if seq is None:
                assert seqs_all_taken(tx, msg.id, m.EVENT)
                continue
            msg.key = (seq, msg.id)
            model.live.append(msg)
            model.event = msg
            model.drawn(msg)
            send(msg)
        elif action == "retry_event" and model.event is not None:
            if model.event.answer is not None:  # answered: it leaves the queue (retried until then)
                msg, model.event = model.event, None
                model.live.remove(msg)
                tx.let_go(msg.key[0], msg.id, msg.answer)
            else:
                send(model.event)
        elif action == "deliver" and model.answers:
            model.deliver(data.draw(st.booleans(), label="answer lost"))
        elif action == "burst" and model.event is None:
            # many quick round trips on a clean line: the seq comes round (reads, or events alone);
            # or reads of one channel the device leaves in its queue while it is busy, each given up
            kind = data.draw(st.sampled_from([m.REQUEST, m.EVENT]), label="burst of")
            busy = kind == m.REQUEST and data.draw(st.booleans(), label="device busy")
            for _ in range(data.draw(BURST, label="burst length")):
                msg = Msg(kind, 1 if busy else data.draw(st.integers(1, 2)), hub_side=kind == m.EVENT)
                if kind == m.EVENT:
                    seq = tx.hold(m.EVENT, msg.id)
                else:
                    msg.p = tx.try_register(kind, msg.id, b"", threaded=True, slot=True)
                    seq = None if msg.p is None else msg.p.seq
                if seq is None:
                    assert len(tx.pending) >= 8 or seqs_all_taken(tx, msg.id, kind)
                    break
                msg.key = (seq, msg.id)
                model.live.append(msg)
                model.drawn(msg)
                model.receive(msg, False)
                model.event = msg if kind == m.EVENT else model.event
                while model.answers and not busy:
                    model.deliver(False)
                model.live.remove(msg)
                if kind == m.EVENT:
                    model.event = None
                    tx.let_go(seq, msg.id, msg.answer)
                else:
                    tx.unregister(msg.p)
        elif action == "hello":  # the hub says hello (same nonce): the device answers in turn
            tx.hello_sent()
            if data.draw(st.booleans(), label="reaches the device"):
                model.answers.append(None)
        elif action == "reboot" and data.draw(st.integers(0, 9)) == 0:
            while model.answers:  # all it sent before it rebooted comes before its new hello
                model.deliver(data.draw(st.booleans(), label="lost in the reboot"))
            model.last_txn, model.event_mem = None, None
            tx.device_rebooted()


def test_a_control_after_255_events_skips_the_remembered_seq() -> None:
    rules = SeqRules(0)
    free = lambda seq, id: False  # noqa: E731
    c = rules.draw(m.CONTROL, 5, free)
    assert c is not None
    rules.control_answered(c)
    for _ in range(255):
        e = rules.draw(m.EVENT, 1, free)
        assert e is not None
        rules.event_ended(e, True)
    assert rules.draw(m.CONTROL, 5, free) not in (c, None)


def test_controls_that_ended_unanswered_are_all_skipped_until_a_read_is_answered() -> None:
    rules = SeqRules(0)
    free = lambda seq, id: False  # noqa: E731
    ended = []
    for _ in range(10):
        s = rules.draw(m.CONTROL, 5, free)
        assert s is not None
        rules.control_ended(s)
        ended.append(s)
    assert set(rules.controls) == set(ended)
    drawn_before = rules.draws
    r = rules.draw(m.REQUEST, 5, free)
    assert r is not None
    rules.other_answered(rules.draws)
    assert rules.controls == {} and rules.draws == drawn_before + 1
    # every seq possibly remembered: no control can be numbered
    rules.controls = {s: rules.draws for s in range(256)}
    assert rules.draw(m.CONTROL, 5, free) is None


def test_an_event_skips_the_last_acked_and_the_previous_event() -> None:
    rules = SeqRules(0)
    free = lambda seq, id: False  # noqa: E731
    a = rules.draw(m.EVENT, 1, free)
    assert a is not None
    rules.event_ended(a, True)
    b = rules.draw(m.EVENT, 1, free)
    assert b is not None
    rules.event_ended(b, False)  # refused: the device still remembers a
    assert rules.events == {a, b}
    for _ in range(600):
        s = rules.draw(m.EVENT, 1, free)
        assert s is not None and s not in (a, b)
        s2 = rules.draw(m.REQUEST, 1, free)
        assert s2 is not None
        for key in ((s, 1), (s2, 1)):  # both answered: nothing of them can come any more
            rules.unanswered.ended(key)
        rules.unanswered.answered((s2, 1))
        assert len(rules.unanswered) <= 4  # a and b (never ended here) and the last two


def test_a_retried_read_takes_a_new_seq_and_a_late_answer_to_the_old_one_is_ignored() -> None:
    tx = make_tx()
    p = tx.try_register(m.REQUEST, 3, b"", threaded=True, slot=True)
    assert p is not None
    tx.transmit(p)
    old = p.seq
    tx.retry(p)
    assert p.seq != old and p.tries == 2
    assert not tx.on_answer(Frame(m.RESPONSE, old, 3, b"\x01"))
    assert tx.on_answer(Frame(m.RESPONSE, p.seq, 3, b"\x02")) and p.answer is not None
    c = tx.try_register(m.CONTROL, 3, b"", threaded=True, slot=True)
    assert c is not None
    tx.transmit(c)
    first = c.seq
    tx.retry(c)
    assert c.tries == 2 and c.seq == first  # a control keeps its seq: the device's duplicate memory
    assert tx.core.link.out[-1] == tx.core.link.out[-2] == bytes((m.CONTROL, first, 3))


def test_threads_beyond_the_limit_wait_asleep_and_go_in_order() -> None:
    tx = make_tx(limit=2)
    held = [tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True) for _ in range(2)]
    assert all(held) and tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True) is None
    order: List[int] = []

    def waiter(i: int) -> None:
        tx.wait_turn_thread()
        p = tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True, granted=True)
        assert p is not None
        order.append(i)
        tx.unregister(p)

    threads = []
    for i in range(5):
        t = threading.Thread(target=waiter, args=(i,), daemon=True)
        t.start()
        threads.append(t)
        deadline = time.monotonic() + 10
        while len(tx.slots.waiting) < i + 1 and time.monotonic() < deadline:
            time.sleep(0.01)
    cpu = time.process_time()
    time.sleep(0.5)
    assert time.process_time() - cpu < 0.25  # asleep, not polling
    assert order == []
    tx.unregister(held[0])  # ends: its slot goes to the first waiter, and on down the line
    for t in threads:
        t.join(10)
    assert order == [0, 1, 2, 3, 4]
    assert tx.slots.used == 1 and not tx.slots.waiting


def test_waiters_fail_with_the_session() -> None:
    tx = make_tx(limit=1)
    assert tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True) is not None
    errors: List[BaseException] = []

    def waiter() -> None:
        try:
            tx.wait_turn_thread()
        except LinkLost as e:
            errors.append(e)

    t = threading.Thread(target=waiter, daemon=True)
    t.start()
    while not tx.slots.waiting:
        time.sleep(0.01)
    tx.fail_all(LinkLost("gone"))
    t.join(10)
    assert len(errors) == 1


def test_coroutines_beyond_the_limit_wait_their_turn() -> None:
    async def main() -> Dict[str, Any]:
        tx = make_tx(limit=1, loop=asyncio.get_running_loop())
        first = tx.try_register(m.REQUEST, 1, b"", slot=True)
        assert first is not None
        got: List[int] = []

        async def waiter(i: int) -> None:
            await tx.wait_turn()
            p = tx.try_register(m.REQUEST, 1, b"", slot=True, granted=True)
            assert p is not None
            got.append(i)
            tx.unregister(p)

        tasks = [asyncio.ensure_future(waiter(i)) for i in range(3)]
        await asyncio.sleep(0.05)
        cancelled = tasks[1]
        cancelled.cancel()  # a waiter that gives up passes its turn on
        await asyncio.sleep(0)
        tx.unregister(first)
        await asyncio.wait_for(asyncio.gather(tasks[0], tasks[2]), 5)
        return {"got": got, "used": tx.slots.used}

    out = asyncio.run(main())
    assert out == {"got": [0, 2], "used": 0}


def test_max_in_flight_is_checked() -> None:
    with pytest.raises(ValueError):
        make_tx(limit=0)
    with pytest.raises(ValueError):
        make_tx(limit=201)


def test_a_late_answer_never_reaches_a_newer_message_of_its_seq_and_id() -> None:
    """The line keeps order, so an answer may come as late as the device likes, but never after the
    answer to anything sent after it (PROTOCOL.md 4.1 rule 3): a (seq, id) is not used again until
    then, however many seqs the hub draws meanwhile."""
    tx = make_tx()
    first = tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True)
    assert first is not None
    tx.transmit(first)
    late = Frame(m.RESPONSE, first.seq, 1, b"\x01")
    tx.unregister(first)  # the hub gave up on it; its answer is still in the device's queue
    sent = [first.seq]
    for _ in range(300):  # the device is busy: the hub keeps reading channel 1, nothing answered
        p = tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True)
        if p is None:
            break
        assert p.seq not in sent, f"seq {p.seq} of channel 1 drawn again while its answer may come"
        sent.append(p.seq)
        tx.transmit(p)
        tx.unregister(p)
    assert len(sent) == 256  # every seq of channel 1 once, then none until the device answers
    assert tx.try_register(m.REQUEST, 2, b"", threaded=True, slot=True) is not None  # other channels go on
    assert not tx.on_answer(late)  # the late answer finds nobody
    assert tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True) is None  # later ones may still come
    tx.on_answer(Frame(m.RESPONSE, sent[-1], 1, b"\x02"))  # the answer to the last one sent
    p = tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True)
    assert p is not None and p.seq != sent[-1]  # everything before it answered or lost, not it


def test_the_devices_hello_reply_shows_every_earlier_answer_came() -> None:
    tx = make_tx()
    for _ in range(256):
        p = tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True)
        assert p is not None
        tx.transmit(p)
        tx.unregister(p)
    assert tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True) is None
    tx.hello_sent()
    p = tx.try_register(m.REQUEST, 2, b"", threaded=True, slot=True)  # sent after the hello
    assert p is not None
    tx.transmit(p)
    tx.unregister(p)
    tx.hello_answered()  # the device answers in order: everything before the hello has come
    for _ in range(255):
        q = tx.try_register(m.REQUEST, 1, b"", threaded=True, slot=True)
        assert q is not None
        tx.unregister(q)
    assert tx.try_register(m.REQUEST, 2, b"", threaded=True, slot=True) is not None
    assert (p.seq, 2) in tx.rules.unanswered  # drawn after the hello: its answer may still come
