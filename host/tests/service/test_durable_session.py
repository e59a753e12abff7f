"""A board's session tied to the service's store (hubwire.daemon.durable), in one process: the
device's retry of an event the service stored but never acknowledged is not stored twice, and hub
events kept by one session are sent by the next."""
from __future__ import annotations

import asyncio
import os
from typing import Any

import pytest

from conftest import Emulator
from hubwire.aio import connect
from hubwire.daemon import durable
from hubwire.daemon.store import Store
from hubwire.testing import repo_root
from hubwire.transport import SerialTransport
from hubwire.wire import messages as m

SOAK = os.path.join(repo_root() or os.getcwd(), "build", "emulator", "hubwire-soak-emulator")


@pytest.fixture
def soak(tmp_path: Any) -> Any:
    if not os.access(SOAK, os.X_OK):
        pytest.fail(f"soak emulator not found at {SOAK}: build it with `make emulator`", pytrace=False)
    emu = Emulator(SOAK, str(tmp_path / "soak"))
    emu.start()
    yield emu
    emu.stop()


async def until(pred: Any, timeout: float, what: str) -> None:
    deadline = asyncio.get_running_loop().time() + timeout
    while not pred():
        assert asyncio.get_running_loop().time() < deadline, f"no {what} within {timeout} s"
        await asyncio.sleep(0.02)


def test_event_stored_but_not_acked_is_stored_once(soak: Emulator, tmp_path: Any) -> None:
    async def run() -> None:
        store = Store(str(tmp_path / "state"))
        dev = await connect(transport=SerialTransport(soak.link), timeout=10, hub_later=True)
        durable.attach(store, "soak", dev)
        bumper = dev.channel("bumper").id
        send = dev.core.link.send_frame

        def no_event_ack(t: int, seq: int, id: int, payload: bytes = b"") -> None:
            if not (t == m.ACK and id == bumper):  # the service dies between storing and acknowledging
                send(t, seq, id, payload)
        dev.core.link.send_frame = no_event_ack  # type: ignore[method-assign]
        assert await dev.call("selftest", 1) == 1
        await until(lambda: store.last_id("soak") == 1, 10, "event stored")
        await dev.close()
        dev = await connect(transport=SerialTransport(soak.link), timeout=10, hub_later=True)  # the next service
        durable.attach(store, "soak", dev)
        await until(lambda: dev.core.stats.events >= 1, 10, "the device's retry")
        assert await dev.call("selftest", 1) == 1  # a new event after it is stored
        await until(lambda: store.last_id("soak") >= 2, 10, "the new event")
        await asyncio.sleep(0.3)
        rows, _missed, last = store.events_after("soak", 0)
        assert [e.id for e in rows] == [1, 2] and last == 2, "the retry is not a second event"
        assert [e.raw for e in rows] == [b"\x01", b"\x01"]
        await dev.close()
        store.close()
    asyncio.run(run())


def test_hub_events_kept_by_one_session_are_sent_by_the_next(soak: Emulator, tmp_path: Any) -> None:
    async def run() -> None:
        store = Store(str(tmp_path / "state"))
        for t in (1, 2, 3):  # kept by a service that stopped before the board was attached
            store.hub_add("soak", "tick", t.to_bytes(4, "little"))
        dev = await connect(transport=SerialTransport(soak.link), timeout=10, hub_later=True)
        durable.attach(store, "soak", dev)
        dev.notify("tick", 4)  # after the kept ones
        await dev.wait_notified(timeout=10)
        assert [await dev.read(c) for c in ("ticks", "tick_first", "tick_last", "tick_twice", "tick_gaps")] == \
            [4, 1, 4, 0, 0]
        assert store.hub_pending("soak") == [], "each one forgotten once the device answered it"
        await dev.close()
        store.close()
    asyncio.run(run())


def test_event_is_stored_before_it_is_acknowledged(soak: Emulator, tmp_path: Any) -> None:
    """The ACK tells the device the event is delivered: the store has it by then."""
    async def run() -> None:
        store = Store(str(tmp_path / "state"))
        dev = await connect(transport=SerialTransport(soak.link), timeout=10, hub_later=True)
        order = []
        send = dev.core.link.send_frame
        bumper = dev.channel("bumper").id

        def spy(t: int, seq: int, id: int, payload: bytes = b"") -> None:
            if t == m.ACK and id == bumper:
                order.append(("ack", store.last_id("soak")))
            send(t, seq, id, payload)
        dev.core.link.send_frame = spy  # type: ignore[method-assign]
        durable.attach(store, "soak", dev)
        assert await dev.call("selftest", 4) == 4
        await until(lambda: len(order) >= 4, 10, "4 events acknowledged")
        assert order[:4] == [("ack", 1), ("ack", 2), ("ack", 3), ("ack", 4)], order
        await dev.close()
        store.close()
    asyncio.run(run())


def test_events_waiting_on_the_board_when_the_service_starts_are_stored(soak: Emulator, tmp_path: Any,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """Events the board kept for the hub while no service ran arrive while the service adopts it
    (asks its board id, slowly here): each one is stored, none taken by the service's own counting."""
    from hubwire.aio import AsyncDevice
    from hubwire.daemon.fleet import Fleet

    board_id = AsyncDevice.board_id

    async def slow_board_id(self: Any, *a: Any, **kw: Any) -> Any:
        await asyncio.sleep(0.5)  # the board's retries come meanwhile
        return await board_id(self, *a, **kw)
    monkeypatch.setattr(AsyncDevice, "board_id", slow_board_id)

    async def run() -> None:
        dev = await connect(transport=SerialTransport(soak.link), timeout=10, hub_later=True)
        send = dev.core.link.send_frame
        bumper = dev.channel("bumper").id
        dev.core.link.send_frame = (  # type: ignore[method-assign]
            lambda t, seq, id, payload=b"": None if (t == m.ACK and id == bumper) else send(t, seq, id, payload))
        assert await dev.call("selftest", 4) == 4  # the board keeps all 4: none acknowledged
        await dev.close()
        store = Store(str(tmp_path / "state"))
        fleet = Fleet(ports=[soak.link], usb=False, udev=False, store=store, cache_dir=str(tmp_path / "cache"))
        await fleet.start()
        try:
            await until(lambda: any(b.key == "soak" and b.device for b in fleet.boards()), 15, "the board adopted")
            await until(lambda: store.last_id("soak") >= 4, 10, "4 events stored")
            await asyncio.sleep(0.3)
            rows, _missed, last = store.events_after("soak", 0)
            assert last == 4 and [e.raw for e in rows] == [b"\x01", b"\x00", b"\x01", b"\x00"]
        finally:
            await fleet.close()
            store.close()
    asyncio.run(run())


@pytest.mark.parametrize("resume", [True, False])
def test_hub_event_in_flight_when_the_service_stops(soak: Emulator, tmp_path: Any, resume: bool) -> None:
    """The device applied a hub event whose ACK the service never got, then the service stopped. The
    next session resumes the hub session kept for the port (same nonce, the event with its seq and
    id): the device acknowledges it again without applying it. A new hub session (``resume`` False)
    is a new hub nonce to the device, which forgets its memory: the event is applied twice."""
    async def run() -> None:
        store = Store(str(tmp_path / "state"))
        port = soak.link
        hs = durable.hub_session(store, port, resume=True)
        assert hs is not None and not hs.resumed, "nothing kept yet: a new hub session"
        dev = await connect(transport=SerialTransport(port), timeout=10, hub_later=True, hub_session=hs)
        assert dev.core.link.nonce == hs.nonce
        durable.attach(store, "soak", dev, port)
        tick = next(c.id for c in dev.descriptor.hub if c.name == "tick")
        on_answer = dev.core.hub.on_answer
        dev.core.hub.on_answer = (  # type: ignore[method-assign]
            lambda f: True if f.type == m.ACK and f.id == tick else on_answer(f))  # the service dies first
        dev.notify("tick", 1)
        await until_async(dev, "tick_last", 1)
        await dev.close()
        kept = store.hub_session(port)
        assert kept is not None and kept.head is not None and kept.head[2] == tick, kept

        hs = durable.hub_session(store, port, resume=resume)  # the restarted service
        assert hs is not None and hs.resumed == resume and (hs.nonce == kept.nonce) == resume
        dev = await connect(transport=SerialTransport(port), timeout=10, hub_later=True, hub_session=hs)
        durable.attach(store, "soak", dev, port)
        await dev.wait_notified(timeout=10)
        dev.notify("tick", 2)  # a new event after it: never taken for the device's memory
        await dev.wait_notified(timeout=10)
        counts = [await dev.read(c) for c in ("ticks", "tick_first", "tick_last", "tick_twice", "tick_gaps")]
        assert counts == ([2, 1, 2, 0, 0] if resume else [3, 1, 2, 1, 0]), counts
        assert store.hub_pending("soak") == []
        got = store.hub_session(port)
        assert got is not None and got.head is None and got.acked is not None, got
        await dev.close()
        store.close()
    asyncio.run(run())


async def until_async(dev: Any, channel: str, value: int, timeout: float = 10) -> None:
    deadline = asyncio.get_running_loop().time() + timeout
    while await dev.read(channel) != value:
        assert asyncio.get_running_loop().time() < deadline, f"{channel} is not {value} after {timeout} s"
        await asyncio.sleep(0.02)


def test_hub_event_waits_while_its_seq_cannot_be_kept(soak: Emulator, tmp_path: Any,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """A hub event goes out only once its seq is on disk (a restart must know what the board may
    remember): while the write fails it waits, then goes out once."""
    async def run() -> None:
        store = Store(str(tmp_path / "state"))
        port = soak.link
        hs = durable.hub_session(store, port, resume=True)
        dev = await connect(transport=SerialTransport(port), timeout=10, hub_later=True, hub_session=hs)
        durable.attach(store, "soak", dev, port)
        fails = []
        hub_sent = store.hub_sent

        def full_disk(*a: Any) -> None:
            if len(fails) < 3:
                fails.append(a)
                raise OSError("database or disk is full")
            hub_sent(*a)
        monkeypatch.setattr(store, "hub_sent", full_disk)
        dev.notify("tick", 1)
        await dev.wait_notified(timeout=10)
        assert len(fails) == 3, "tried again after each failure"
        assert [await dev.read(c) for c in ("ticks", "tick_last", "tick_twice")] == [1, 1, 0]
        got = store.hub_session(port)
        assert got is not None and got.acked is not None and got.head is None, got
        await dev.close()
        store.close()
    asyncio.run(run())
