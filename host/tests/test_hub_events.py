"""Hub events to a scripted device: exactly once and in order through lost acks, a cut line and a
reboot; checks at notify(); the device's measured heartbeat; asyncio handlers; hubwire info."""
from __future__ import annotations

import struct
import threading
import time
from typing import Any, List

import pytest

import hubwire
from hubwire import HubChannelError, HubChannels
from hubwire.wire import messages as m

from hubdevice import HubDevice, connect, f32, full_hub, wait_for


# ------------------------------------------------------------------------------ hub events


def test_events_exactly_once_in_order_with_lost_acks() -> None:
    # the device loses its first ACK of every event: the hub retries each with the same seq
    with HubDevice(ack_event=lambda seq, nth: nth > 0) as dev, connect(dev, hub=full_hub([])) as d:
        for i in range(10):
            d.notify("mode", i)
        assert wait_for(lambda: d.notifications_pending == 0)
        assert dev.events == [(4, bytes((i,))) for i in range(10)]
        assert dev.event_frames >= 20 and d.session.stats.hub_events_delivered == 10
        assert d.session.stats.hub_event_retries >= 10


def test_events_ride_through_link_loss_and_reboot() -> None:
    lost = threading.Event()
    with HubDevice() as dev, connect(dev, hub=full_hub([]), on_link_lost=lost.set) as d:
        assert wait_for(lambda: len(dev.binds) == 1)
        d.notify("mode", 1)
        assert wait_for(lambda: dev.events == [(4, b"\x01")])
        dev.mute = True                       # the line is cut: the hub declares the link lost
        for i in (2, 3, 4):
            d.notify("mode", i)
        assert lost.wait(5) and d.notifications_pending == 3
        dev.mute = False                      # back: the link is restored, the queue drains in order
        assert wait_for(lambda: d.notifications_pending == 0)
        assert dev.events == [(4, bytes((i,))) for i in (1, 2, 3, 4)]
        binds = len(dev.binds)
        dev.mute = True
        d.notify("mode", 5)
        time.sleep(0.3)
        dev.mute = False
        dev.reboot()                          # a new device session: bound again, then delivered
        assert wait_for(lambda: d.notifications_pending == 0)
        assert dev.events[-1] == (4, b"\x05") and len(dev.events) == 5
        assert len(dev.binds) > binds and d.session.stats.reboots == 1


def test_device_write_memory_is_per_device_session() -> None:
    calls: List[int] = []
    with HubDevice() as dev, connect(dev) as d:
        d.accept("target", calls.append, type="i16")
        assert wait_for(lambda: dev.binds and dev.binds[-1][5] == 0)
        seq = dev._seq + 1
        assert dev.ask(m.CONTROL, 5, struct.pack("<h", 1), seq=seq).type == m.ACK  # type: ignore[union-attr]
        n = len(dev.binds)
        dev.reboot()
        assert wait_for(lambda: len(dev.binds) > n)  # rediscovered (from memory) and bound again
        assert dev.ask(m.CONTROL, 5, struct.pack("<h", 1), seq=seq).type == m.ACK  # type: ignore[union-attr]
        assert calls == [1, 1]  # the same seq and id from the new boot is a new write


def test_not_linked_nak_keeps_the_event_and_relinks() -> None:
    with HubDevice() as dev, connect(dev, hub=full_hub([])) as d:
        assert wait_for(lambda: len(dev.binds) == 1)
        dev.not_linked = 1      # the next event is answered NOT_LINKED: it must not count as delivered
        hellos = dev.hellos
        d.notify("mode", 9)
        assert wait_for(lambda: dev.events == [(4, b"\x09")])
        assert dev.hellos > hellos and d.session.stats.not_linked == 1
        # the device holds the event before the hub has its ACK: wait for the hub to count it
        assert wait_for(lambda: d.session.stats.hub_events_delivered == 1)
        assert d.session.stats.hub_events_refused == 0


def test_not_linked_bind_report_is_sent_again() -> None:
    with HubDevice() as dev:
        dev.not_linked = 1      # the first bind report meets a device that dropped the link
        with connect(dev, hub=full_hub([])) as d:
            assert wait_for(lambda: len(dev.binds) == 1 and dev.hellos >= 2)
            d.notify("mode", 1)
            assert wait_for(lambda: dev.events == [(4, b"\x01")])


def test_wait_notified_returns_once_every_event_is_acknowledged() -> None:
    with HubDevice(ack_event=lambda seq, nth: nth > 0) as dev, connect(dev, hub=full_hub([])) as d:
        for i in range(5):
            d.notify("mode", i)
        d.wait_notified(10)
        assert dev.events == [(4, bytes((i,))) for i in range(5)]  # no waiting: all were acked
        dev.mute = True
        d.notify("mode", 9)
        with pytest.raises(hubwire.Timeout, match="1 hub events still wait"):
            d.wait_notified(0.3)
        dev.mute = False
        d.wait_notified(10)
        assert dev.events[-1] == (4, b"\x09")


def test_events_wait_for_the_bind_report_and_are_checked() -> None:
    hub = HubChannels()
    hub.event("mode", type="u8")
    with HubDevice() as dev, connect(dev) as d:
        with pytest.raises(HubChannelError, match="thermo takes no hub event 'nosuch'; it takes: mode"):
            d.notify("nosuch", 1)
        d.provide("setpoint", 1.0)
        with pytest.raises(HubChannelError, match="not an event"):
            d.notify("setpoint", 1.0)
        d.event("mode", type="u8")
        with pytest.raises(hubwire.InvalidValue):
            d.notify("mode", 300)
        d.notify("mode", 3)
        assert wait_for(lambda: dev.events == [(4, b"\x03")])
        assert dev.binds and dev.binds[-1][4] == 0
    with pytest.raises(hubwire.HubwireError, match="closed"):
        d.notify("mode", 4)


# ---------------------------------------------------------------------------------- health


def test_health_shows_the_device_measured_heartbeat() -> None:
    with HubDevice(beat_ms=237) as dev, connect(dev) as d:
        assert wait_for(lambda: d.health().measured_heartbeat_ms == 237)


def test_aio_coroutine_action() -> None:
    import asyncio

    async def main() -> None:
        with HubDevice() as dev:
            async with hubwire.aio.connect(dev.path, timeout=5, cache_dir=False, hub_later=True) as d:
                got: List[float] = []

                @d.action("dock")
                async def dock(speed: float) -> bool:
                    await asyncio.sleep(0.01)
                    got.append(speed)
                    return True
                d.provide("setpoint", lambda: 4.0, type="f32")
                await asyncio.sleep(0)
                loop = asyncio.get_running_loop()
                assert await loop.run_in_executor(None, wait_for, lambda: bool(dev.binds) and dev.binds[-1][3] == 0)
                a = await loop.run_in_executor(None, dev.ask, m.CONTROL, 3, f32(1.5))
                assert a is not None and a.payload == b"\x01" and got == [1.5]
                r = await loop.run_in_executor(None, dev.ask, m.REQUEST, 1)
                assert r is not None and r.payload == f32(4.0)
    asyncio.run(main())


def test_info_lists_the_hub_channels_the_device_uses(tmp_path: Any) -> None:
    import json
    import os
    import subprocess
    import sys

    env = dict(os.environ, HUBWIRE_CACHE_DIR=str(tmp_path))
    with HubDevice() as dev:
        out = subprocess.run([sys.executable, "-m", "hubwire", "info", dev.path, "--json"], capture_output=True,
                             text=True, env=env, timeout=60)
        assert out.returncode == 0, out.stderr
        hub = json.loads(out.stdout)["hub"]
        assert [(c["id"], c["name"], c["access"], c["type"]) for c in hub][:3] == [
            (1, "setpoint", "r", "f32"), (2, "report", "w", "struct{temp: f32, heater: bool}"), (3, "dock", "c", "(f32) -> bool")]
        text = subprocess.run([sys.executable, "-m", "hubwire", "info", dev.path], capture_output=True, text=True,
                              env=env, timeout=60).stdout
        table = text.split("hub channels thermo uses")[1]
        assert "mode" in table and "event" in table and "temp" not in table.split("struct")[0]


def test_aio_connect_with_hub_channels_and_notify() -> None:
    import asyncio

    async def main() -> None:
        with HubDevice() as dev:
            hub = full_hub([])
            hub.remove("target")
            with pytest.raises(HubChannelError, match="writes hub channel 'target'"):
                await hubwire.aio.connect(dev.path, timeout=5, cache_dir=False, hub=hub)
            hub.accept("target", type="i16")
            async with hubwire.aio.connect(dev.path, timeout=5, cache_dir=False, hub=hub) as d:
                for i in (7, 8):
                    d.notify("mode", i)
                await d.wait_notified(10)
                assert dev.events == [(4, b"\x07"), (4, b"\x08")] and d.notifications_pending == 0
                assert d.hub_binding()["target"] == "ok"
    asyncio.run(main())
