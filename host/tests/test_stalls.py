"""A stalled line or a busy machine: what the hub reads late is still what the device said.

A device that lost the link announces itself (once a second, and in answer to each hub heartbeat)
until the hub's answer reaches it. Held up on a stalled line or a busy machine, several are read at
once: they are one loss on the device's side, each answered, not one loss (callbacks, streams ended,
"restored") per hello (PROTOCOL.md 4.2, rule 3). And a device gone silent is lost by silence, its
port kept open."""
from __future__ import annotations

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


def test_a_loss_check_on_a_quiet_port_does_not_take_it_for_gone() -> None:
    """A raw tty read with nothing waiting returns no bytes, as at end of file: nothing may read the
    port but what select() says holds bytes, so a silent device is lost by silence, its port kept
    open (a read on the loss check once took it for gone, opened it again with a new hub nonce, and
    the device, forgetting its duplicate memory, took a retried hub event twice)."""
    with HubDevice() as dev, connect(dev) as d:
        assert wait_for(lambda: d.state == "ready")
        stats = d.session.stats
        reopens, lost = stats.port_reopens, stats.link_lost
        dev.mute = True
        assert wait_for(lambda: stats.link_lost > lost, 10)
        dev.mute = False  # a port that had been closed would have to be opened again first
        assert wait_for(lambda: d.state == "ready", 10)
        assert stats.port_reopens == reopens
