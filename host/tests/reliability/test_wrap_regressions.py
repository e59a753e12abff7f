"""Exactly once across the wrap of the hub's 8-bit seq (PROTOCOL.md 4.1, 4.4, 10.3), against the real
device library in the soak emulator (extras/tests/Soak), counted by the sketch itself:

- a hub event after exactly 255 other hub transactions would carry the seq of the one before it;
- a write after exactly 255 hub events would carry the seq of the write before it (hub events do
  not end the device's duplicate window for controls);
- 257 reads of one channel in flight at once: every (seq, id) of that channel is taken.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from typing import Any, Iterator

import pytest

import hubwire
from hubwire.testing.faultlink import stop_process
from hubwire.testing.faultlink.soak import soak_emulator_binary, start_emulator
from hubwire.testing.faultlink.soak_hub import HubTraffic


def _binary() -> str:
    binary = soak_emulator_binary()
    if not os.access(binary, os.X_OK):
        pytest.fail(f"soak emulator not found at {binary}: build it with `make emulator`", pytrace=False)
    return binary


@pytest.fixture
def soak(tmp_path: Any) -> Iterator[Any]:
    link = str(tmp_path / "soak")
    emu = start_emulator(_binary(), link)
    try:
        with hubwire.connect(link, cache_dir=False, timeout=10, hub=HubTraffic().hub,
                             retry_timeout=0.5, tries=10) as dev:
            yield dev
    finally:
        stop_process(emu)


def test_a_hub_event_after_255_reads_is_delivered(soak: Any) -> None:
    dev = soak
    dev.notify("tick", 1)
    dev.wait_notified(20)
    for _ in range(255):
        dev.read("uptime")
    dev.notify("tick", 2)
    dev.wait_notified(20)
    assert dev.session.stats.hub_events_delivered == 2
    # the sketch's own count: its handler ran for both, in order, none twice
    assert (dev.ticks, dev.tick_last, dev.tick_twice) == (2, 2, 0)


def test_a_write_after_255_hub_events_is_applied(soak: Any) -> None:
    dev = soak
    dev.write("token", 101)
    for i in range(255):
        dev.notify("tick", i + 1)
    dev.wait_notified(60)  # no read in between: a hub R would end the device's window for controls
    dev.write("token", 102)
    assert dev.ticks == 255
    assert (dev.token, dev.tokens_applied, dev.twice) == (102, 2, 0)


_CONCURRENT = textwrap.dedent("""
    import sys, threading, time
    import hubwire
    from hubwire.testing.faultlink import stop_process
    from hubwire.testing.faultlink.soak import start_emulator

    binary, link, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
    emu = start_emulator(binary, link)
    try:
        with hubwire.connect(link, cache_dir=False, timeout=10, retry_timeout=0.5, tries=40, hub_later=True) as dev:
            tx = dev.session.core.tx
            hold = threading.Event()
            hold.set()
            on_answer = tx.on_answer
            tx.on_answer = lambda f: False if hold.is_set() else on_answer(f)  # answers lost meanwhile
            results, started = [], []

            def read():
                started.append(1)
                results.append(dev.read("uptime"))

            threads = [threading.Thread(target=read, daemon=True) for _ in range(n)]
            for t in threads:
                t.start()
            end = time.monotonic() + 20
            while (len(started) < n or len(tx.pending) < min(n, 64)) and time.monotonic() < end:
                time.sleep(0.05)
            time.sleep(0.5)  # the last ones look for a seq
            cpu = time.process_time()
            time.sleep(1.0)
            cpu = time.process_time() - cpu
            print("pending", len(tx.pending), "cpu", round(cpu, 2), flush=True)
            hold.clear()
            for t in threads:
                t.join(30)
            print("done", len(results), "cpu", round(cpu, 2), flush=True)
    finally:
        stop_process(emu)
""")


def test_257_concurrent_reads_of_one_channel_all_complete_without_spinning(tmp_path: Any) -> None:
    # in a process of its own: a hub that spins holding its lock cannot even be closed
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
    proc = subprocess.Popen([sys.executable, "-c", _CONCURRENT, _binary(), str(tmp_path / "soak"), "257"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)  # the script and its emulator
        out, err = proc.communicate()
        pytest.fail(f"257 concurrent reads did not end within 120 s: {out!r}")
    done = [ln for ln in out.split("\n") if ln.startswith("done")]
    assert done, (out, err[-2000:])
    words = done[0].split()
    assert int(words[1]) == 257, out
    # nothing spun while the answers were held back: far less than one core for that second
    assert float(words[3]) < 0.5, out


def test_a_write_when_every_seq_may_be_remembered_reads_first_and_is_applied(soak: Any) -> None:
    # as after 256 writes that all ended unanswered: no seq is safe for a control until the device
    # has answered another transaction (a read of id 0), and then the write goes through, once
    dev = soak
    tx = dev.session.core.tx
    unmatched = dev.session.stats.unmatched_answers
    with tx.lock:
        tx.rules.controls = {s: tx.rules.draws for s in range(256)}
    dev.write("token", 7)
    assert tx.rules.controls and len(tx.rules.controls) == 1  # the write's own seq, answered
    assert (dev.token, dev.tokens_applied) == (7, 1)
    assert dev.session.stats.unmatched_answers == unmatched


def test_asyncio_reads_beyond_max_in_flight_wait_their_turn(tmp_path: Any) -> None:
    import asyncio

    import hubwire.aio

    link = str(tmp_path / "soak")
    emu = start_emulator(_binary(), link)

    async def main() -> Any:
        async with hubwire.aio.connect(link, cache_dir=False, timeout=10, max_in_flight=4, hub_later=True) as dev:
            tx = dev._core.tx
            peak = 0
            register = tx.try_register

            def counting(*a: Any, **kw: Any) -> Any:
                nonlocal peak
                p = register(*a, **kw)
                peak = max(peak, tx.slots.used)
                return p

            tx.try_register = counting
            values = await asyncio.gather(*(dev.read("uptime") for _ in range(40)))
            return len(values), peak, tx.slots.used, len(tx.slots.waiting)

    try:
        assert asyncio.run(main()) == (40, 4, 0, 0)
    finally:
        stop_process(emu)


def test_a_bind_report_when_every_seq_may_be_remembered_reads_first_and_is_acked(soak: Any) -> None:
    dev = soak
    core = dev.session.core
    tx = core.tx
    sent, delivered = core.stats.binds_sent, core.stats.hub_events_delivered
    with tx.lock:
        tx.rules.controls = {s: tx.rules.draws for s in range(256)}
    core.loop.call_soon_threadsafe(core.hub.rebind)
    end = time.monotonic() + 20
    while (core.stats.binds_sent == sent or core.hub._bind is not None) and time.monotonic() < end:
        time.sleep(0.05)
    # sent once, and acked: the device remembers its seq, and no other
    assert core.stats.binds_sent == sent + 1 and core.hub._bind is None
    assert len(tx.rules.controls) == 1
    dev.notify("tick", 5)
    dev.wait_notified(20)
    assert core.stats.hub_events_delivered == delivered + 1
    assert (dev.ticks, dev.tick_last) == (1, 5)


def test_a_loop_request_waits_for_a_threads_control_to_end(soak: Any) -> None:
    """The synchronous API's controls have a gate of their own; a request the loop makes itself (a
    stream resumed, a subscribe) must still not go between the tries of one: the device would take
    the retry for a new write (PROTOCOL.md 4.1)."""
    import asyncio
    import threading

    from hubwire.wire import messages as m

    dev = soak
    core = dev.session.core
    tx = core.tx
    left = dev.session.descriptor.by_name("left").id
    lost = threading.Event()
    on_answer = tx.on_answer

    def drop_first_control_answer(f: Any) -> bool:
        if f.type in (m.ACK, m.NAK) and tx.control_owner == "user" and not lost.is_set():
            lost.set()  # the write's first ACK is lost: the hub will send the write again
            return False
        return on_answer(f)

    tx.on_answer = drop_first_control_answer
    before = dev.tokens_applied
    writer = threading.Thread(target=dev.write, args=("token", 777))
    writer.start()
    assert lost.wait(20)
    # the loop's own request while the write waits for its retry
    fut = asyncio.run_coroutine_threadsafe(tx.transact(m.REQUEST, left), core.loop)
    fut.result(20)
    writer.join(20)
    tx.on_answer = on_answer
    assert (dev.token, dev.tokens_applied - before, dev.twice) == (777, 1, 0)
