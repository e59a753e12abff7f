"""Hub channels through `hubwire serve` (docs/SERVICE.md "Hub channels"): a client of the service
provides the hub channels the soak board expects (a write `tally`, an action `bump`, an event
`tick`) with the same API as a direct connection; a second provider is refused naming both; when
the provider goes away the board is told the channel is unbound."""
from __future__ import annotations

import asyncio
import os
import threading
import time
from typing import Iterator, List

import pytest

import hubwire
import hubwire.aio
from conftest import Emulator
from hubwire.errors import HubChannelError, HubwireError
from hubwire.testing import repo_root

from .conftest import Serve, wait_for

SOAK = os.path.join(repo_root() or os.getcwd(), "build", "emulator", "hubwire-soak-emulator")


@pytest.fixture
def soak(boards_dir: str) -> Iterator[Emulator]:
    if not os.access(SOAK, os.X_OK):
        pytest.fail(f"soak emulator not found at {SOAK}: build it with `make emulator`", pytrace=False)
    emu = Emulator(SOAK, os.path.join(boards_dir, "soak"))
    emu.start()
    yield emu
    emu.stop()


class Tally:
    """The hub's half of the soak sketch: records every tally written and every bump called."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.tallies: List[int] = []
        self.bumps: List[int] = []
        self.hub = hubwire.HubChannels("tally-keeper")
        self.hub.accept("tally", self.on_tally, type="u32")
        self.hub.action("bump", self.on_bump, type="u32", returns="u32")
        self.hub.event("tick", type="u32")

    def on_tally(self, token: int) -> None:
        with self.lock:
            self.tallies.append(token)

    def on_bump(self, n: int) -> int:
        with self.lock:
            self.bumps.append(n)
        return n + 1


def test_a_client_provides_the_boards_hub_channels_through_the_service(serve: Serve, soak: Emulator) -> None:
    serve.wait_state("soak", "ready")
    t = Tally()
    with hubwire.connect("soak", hub=t.hub) as dev:
        assert dev.url == "service:soak"
        assert dev.hub is t.hub
        wait_for(lambda: dev.hub_binding() == {"tally": "ok", "bump": "ok", "tick": "ok"}, what="bound")
        dev.hub_load = True
        wait_for(lambda: dev.tally_acked >= 20 and dev.bump_ok >= 4, what="tallies and bumps through the service")
        dev.hub_load = False
        wait_for(lambda: dev.tally_acked + dev.tally_failed == dev.tally_token, what="the last tally answered")
        # every tally the board saw acknowledged reached this client's handler, each once and in order
        # (one that timed out on the board, 240 on a loaded machine, may or may not have)
        with t.lock:
            acked, failed = dev.tally_acked, dev.tally_failed
            assert t.tallies == sorted(set(t.tallies)), t.tallies
            assert acked <= len(t.tallies) <= acked + failed
            assert dev.last_hub_failure in (0, 240)
        assert dev.bump_wrong == 0 and dev.bump_ok >= 4
        # a hub event from this client, with the same call as direct
        before = dev.ticks
        dev.notify("tick", 7)
        dev.wait_notified(10)
        wait_for(lambda: dev.ticks == before + 1, what="tick applied")
        info = serve.cli("info", "soak").stdout
        provided = info[info.index("provided through hubwire serve"):]
        assert f"pid {os.getpid()}" in provided and "tally" in provided, info


def test_a_second_provider_is_refused_naming_both(serve: Serve, soak: Emulator) -> None:
    serve.wait_state("soak", "ready")
    first, second = Tally(), Tally()
    with hubwire.connect("soak", hub=first.hub):
        with pytest.raises(HubwireError) as e:
            hubwire.connect("soak", hub=second.hub)
        text = str(e.value)
        assert text.count("pid") == 2 and "tally" in text, text
        assert f"pid {os.getpid()}" in text


def test_the_board_is_told_unbound_when_the_provider_goes(serve: Serve, soak: Emulator) -> None:
    serve.wait_state("soak", "ready")
    t = Tally()
    watcher = hubwire.connect("soak")
    try:
        with hubwire.connect("soak", hub=t.hub) as dev:
            wait_for(lambda: dev.hub_binding()["tally"] == "ok", what="bound")
        # the provider left: the board's binding fails (its failsafe / unbound path), the service says so
        wait_for(lambda: watcher.hub_binding()["tally"] == "UNKNOWN_CHANNEL", what="unbound")
        # the sketch writes its tally only while bound (hubBinding().ok()): nothing more is written
        acked, token = watcher.tally_acked, watcher.tally_token
        watcher.hub_load = True
        time.sleep(1.0)  # 50 of the sketch's 20 ms steps
        assert (watcher.tally_acked, watcher.tally_token) == (acked, token)
        watcher.hub_load = False
        rows = {r["channel"]: r for r in watcher.session.hub_status()}
        assert rows["tally"]["by"] is None and rows["tally"]["status"] == "unbound", rows
        # a new provider binds it again
        t2 = Tally()
        with hubwire.connect("soak", hub=t2.hub) as dev:
            wait_for(lambda: dev.hub_binding()["tally"] == "ok", what="bound again")
    finally:
        watcher.close()


def test_the_asyncio_face_provides_too(serve: Serve, soak: Emulator) -> None:
    serve.wait_state("soak", "ready")

    async def main() -> int:
        hub = hubwire.HubChannels()
        seen: List[int] = []

        async def on_tally(token: int) -> None:
            seen.append(token)
        hub.accept("tally", on_tally, type="u32")
        hub.action("bump", lambda n: n + 1, type="u32", returns="u32")
        hub.event("tick", type="u32")
        async with hubwire.aio.connect("soak") as watcher:
            assert watcher.hub_binding() == {"tally": "UNKNOWN_CHANNEL", "bump": "UNKNOWN_CHANNEL", "tick": "ok"}
        async with hubwire.aio.connect("soak", hub=hub) as dev:
            assert dev.hub is hub
            assert dev.hub_binding() == {"tally": "ok", "bump": "ok", "tick": "ok"}
            await dev.write("hub_load", True)
            for _ in range(400):
                if len(seen) >= 10:
                    break
                await asyncio.sleep(0.05)
            await dev.write("hub_load", False)
            dev.notify("tick", 3)
            await dev.wait_notified(10)
        return len(seen)

    assert asyncio.run(main()) >= 10


def test_a_type_the_board_does_not_expect_raises_as_direct(serve: Serve, soak: Emulator) -> None:
    serve.wait_state("soak", "ready")
    hub = hubwire.HubChannels()
    hub.accept("tally", lambda v: None, type="u16")
    hub.action("bump", lambda n: n, type="u32", returns="u32")
    hub.event("tick", type="u32")
    with pytest.raises(HubChannelError, match="tally"):
        hubwire.connect("soak", hub=hub)


def test_notify_and_hub_on_a_routed_device_without_hub_channels(serve: Serve, soak: Emulator) -> None:
    """Before: ``dev.notify`` and ``dev.hub`` raised AttributeError through the service."""
    serve.wait_state("soak", "ready")
    with hubwire.connect("soak") as dev:
        assert isinstance(dev.hub, hubwire.HubChannels)
        before = dev.ticks
        dev.notify("tick", 11)  # the board's own type when the caller declared none
        dev.wait_notified(10)
        wait_for(lambda: dev.ticks == before + 1, what="tick applied")
        with pytest.raises(HubChannelError):
            dev.notify("tally", 1)  # not an event of the board


def test_what_a_client_sends_to_provide_is_checked(serve: Serve, soak: Emulator) -> None:
    """The socket ops as any program would send them: malformed requests are answered with an
    error, a client's name is shown quoted, and a refusal reaches the board as REJECTED."""
    from hubwire.wire.messages import NakCode

    from .test_serve_durable import ready_client

    c = ready_client(serve, "soak")
    try:
        assert c.request("provide", board="soak", sub="p", channels="tally")["error"] == "Usage"
        bad = c.request("provide", board="soak", sub="p", channels=[{"n": "tally", "a": "w", "t": "nope"}])
        assert not bad["ok"] and "tally" in bad["message"]
        both = [{"n": "tally", "a": "w", "t": "u32"}, {"n": "bump", "a": "c", "t": "u32", "rt": "u32"}]
        ok = c.request("provide", board="soak", sub="p", name="\x1b[31mevil\n", channels=both)
        assert ok["ok"], ok
        by = {r["channel"]: r["by"] for r in c.request("hub", board="soak")["hub"]}["tally"]
        assert "\x1b" not in by and "\n" not in by and "\\x1b[31mevil\\n" in by, by
        assert c.request("hub_answer", sub="nope", req=1)["error"] == "Usage"
        assert c.request("hub_answer", sub="p", req=1, raw="zz")["error"] == "Usage"
        assert c.request("hub_answer", sub="p", req=99999)["ok"]  # unknown: dropped
        wait_for(lambda: c.request("read", board="soak", channel="hub_load")["ok"], what="readable")
        failed = c.request("read", board="soak", channel="tally_failed")["value"]
        c.send("write", board="soak", channel="hub_load", value=True)
        refused = 0
        while refused < 3:  # refuse the board's writes as they come (it writes only while bound)
            msg = c.pump()
            if isinstance(msg.get("hub"), dict):
                c.send("hub_answer", sub="p", req=msg["hub"]["req"], error="REJECTED")
                refused += msg["hub"]["channel"] == "tally"
        c.request("write", board="soak", channel="hub_load", value=False)
        wait_for(lambda: c.request("read", board="soak", channel="tally_failed")["value"] >= failed + 3,
                 what="refusals counted on the board")
        assert c.request("read", board="soak", channel="last_hub_failure")["value"] in (NakCode.REJECTED, 240)
    finally:
        c.close()
