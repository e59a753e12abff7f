"""A stalled line or a busy machine: what the hub reads late is still what the device said.

A device that lost the link announces itself (once a second, and in answer to each hub heartbeat)
until the hub's answer reaches it. Held up on a stalled line or a busy machine, several are read at
once: they are one loss on the device's side, each answered, not one loss (callbacks, streams ended,
"restored") per hello (PROTOCOL.md 4.2, rule 3). And a hub whose loop was held up by a long callback
reads what its port holds before it calls the link lost (4.3)."""
from __future__ import annotations

import asyncio
import threading
import time

from hubwire.session.link import LOSS_HEARTBEATS

from hubdevice import HubDevice, connect, wait_for


def test_a_backlog_of_announcements_is_one_loss_on_the_device_side() -> None:
    with HubDevice() as dev, connect(dev) as d:
        assert wait_for(lambda: d.state == "ready")
        s = d.session.stats
        lost, restored, rehandshakes, hellos = s.link_lost, s.link_restored, s.rehandshakes, dev.hellos
        dev.announce(times=5)
        assert wait_for(lambda: dev.hellos >= hellos + 5)  # each one answered
        assert (s.link_lost - lost, s.link_restored - restored, s.rehandshakes - rehandshakes) == (1, 1, 1)
        assert d.state == "ready"


def test_an_announcement_after_the_device_linked_again_is_a_new_loss() -> None:
    with HubDevice() as dev, connect(dev) as d:
        assert wait_for(lambda: d.state == "ready")
        s = d.session.stats
        lost = s.link_lost
        dev.announce()
        assert wait_for(lambda: s.link_lost == lost + 1)
        # linked again: a later announcement (the device lost the hub once more) counts
        beats = d.session.core.link.peer_hb_count
        assert wait_for(lambda: d.session.core.link.peer_hb_count >= beats + 4)
        dev.announce()
        assert wait_for(lambda: s.link_lost == lost + 2)


def test_a_loss_check_held_up_by_a_long_callback_reads_the_port_first() -> None:
    """The loss check due right after a long callback (the same turn of the loop, before the loop
    looks at its ports again) sees the device's heartbeats waiting in the port, not silence."""
    with HubDevice() as dev, connect(dev) as d:
        assert wait_for(lambda: d.state == "ready")
        link = d.session.core.link
        limit = LOSS_HEARTBEATS * link.device_hello.heartbeat_ms / 1000
        lost = d.session.stats.link_lost
        done = threading.Event()

        def long_callback_then_the_check() -> None:
            beats = dev.beats
            # the loop is held up past the loss deadline while the device goes on beating
            while time.monotonic() - link.last_rx <= limit or dev.beats < beats + 2:
                time.sleep(0.01)
            link._loss_check()
            done.set()
        loop: asyncio.AbstractEventLoop = link.loop
        loop.call_soon_threadsafe(long_callback_then_the_check)
        assert done.wait(30)
        assert d.session.stats.link_lost == lost and link.linked
