"""Reconnects: the pty disappears (the device process dies, its link is removed, or the proxy in
front of it goes away) and comes back on the same path. The hub must notice, tell the application,
fail calls fast with LinkLost meanwhile, re-open the port with backoff, and carry on."""
from __future__ import annotations

import time
from typing import Any

import pytest

import hubwire
from hubwire.errors import LinkLost

from hubwire.testing import tap_of, tapped
from hubwire.transport import SerialTransport

from .conftest import Emu, FaultLink, FaultyTransport, tty_fds, hubwire_thread_ids, hubwire_threads, settle, wait_until

FAIL_FAST = 0.5  # seconds a call may take to raise LinkLost while the link is down


def record_callbacks(dev: Any) -> dict:
    seen: dict = {"link_lost": [], "link_restored": [], "reconnect": []}
    dev.on("link_lost", lambda: seen["link_lost"].append(time.monotonic()))
    dev.on("link_restored", lambda: seen["link_restored"].append(time.monotonic()))
    dev.on("reconnect", lambda d: seen["reconnect"].append((time.monotonic(), d.name)))
    return seen


def assert_fails_fast(dev: Any) -> None:
    for op in (lambda: dev.battery, lambda: setattr(dev, "left", 0.1), lambda: dev.selftest(1)):
        t = time.monotonic()
        with pytest.raises(LinkLost):
            op()
        took = time.monotonic() - t
        assert took < FAIL_FAST, f"a call while the link is down took {took:.2f} s to fail"


def test_device_dies_and_comes_back_on_the_same_path(emu: Emu) -> None:
    with hubwire.connect(transport=tapped(emu.link), cache_dir=False) as dev:
        seen = record_callbacks(dev)
        attempts = tap_of(dev).opens  # when the hub tried to open the port
        dev.left = 0.5
        emu.kill()  # the process dies, its pty and link vanish
        wait_until(lambda: dev.state == "lost", 3, "link lost")
        assert_fails_fast(dev)
        down = time.monotonic()
        time.sleep(3.0)  # stays away a while: the hub must back off, not spin
        during = [t for t in attempts if t >= down]
        emu.start()
        wait_until(lambda: dev.state == "ready", 10, "ready again")
        assert settle(lambda: len(seen["reconnect"]) == 1, 3)
        assert len(seen["link_lost"]) == 1
        # a new boot: nothing restored by the hub, the application was told via on_reconnect
        assert dev.left == 0.0 and dev.applied == 0
        dev.left = 0.25
        assert dev.left == 0.25
        # backoff: a handful of attempts in 3 s, spaced further and further apart
        assert 2 <= len(during) <= 15, f"{len(during)} open attempts in 3 s"
        gaps = [b - a for a, b in zip(during, during[1:])]
        assert max(gaps) >= 0.4, f"no backoff: gaps {gaps}"
        assert dev.session.stats.reboots == 1 and dev.session.stats.port_reopens >= 1


def test_proxy_pty_vanishes_while_the_device_keeps_running(emu: Emu, tmp_path: Any) -> None:
    """Like a USB cable pulled and plugged back in: same path, same (still running) device."""
    link = str(tmp_path / "usb")
    fl = FaultLink(emu.link, link).start()
    try:
        with hubwire.connect(link, cache_dir=False) as dev:
            seen = record_callbacks(dev)
            nonce = dev.session.device_hello.nonce
            dev.left = 0.5
            fl.stop()  # the hub's pty and its link disappear
            wait_until(lambda: dev.state == "lost", 3, "link lost")
            assert_fails_fast(dev)
            time.sleep(1.5)  # long enough for the device's failsafe (4 x 250 ms of silence)
            fl = FaultLink(emu.link, link).start()  # plugged back in, same path
            wait_until(lambda: dev.state == "ready", 10, "ready again")
            assert settle(lambda: len(seen["link_restored"]) == 1, 3), seen
            assert len(seen["link_lost"]) == 1 and seen["reconnect"] == []
            assert dev.session.device_hello.nonce == nonce  # the same device session
            assert dev.failsafes == 1 and dev.left == 0.0  # the device noticed and stopped the motor
            dev.left = 0.75
            assert dev.left == 0.75 and dev.applied == 2
    finally:
        fl.stop()


def test_stall_longer_than_the_loss_timeout(emu: Emu) -> None:
    """The line stops for 2.5 s (bytes held, then delivered): both sides declare the link lost,
    calls fail fast meanwhile, then everything recovers by itself."""
    fl = FaultyTransport(SerialTransport(emu.link))
    with hubwire.connect(transport=fl, cache_dir=False) as dev:
        seen = record_callbacks(dev)
        dev.left = 0.5
        fl.stall(2500)
        wait_until(lambda: dev.state == "lost", 3, "link lost")
        assert_fails_fast(dev)
        wait_until(lambda: dev.state == "ready", 10, "ready again")
        assert settle(lambda: len(seen["link_restored"]) >= 1, 3), seen
        assert dev.battery > 0
        assert dev.failsafes == 1
        assert dev.session.stats.reboots == 0
        assert fl.stats()["h2d"]["stalls"] == 1


def test_repeated_restarts_leak_no_threads_or_fds(emu: Emu) -> None:
    with hubwire.connect(emu.link, cache_dir=False) as dev:
        dev.left = 0.5
        threads0, fds0 = hubwire_thread_ids(), tty_fds()
        for i in range(3):
            emu.stop()
            wait_until(lambda: dev.state == "lost", 3, "link lost")
            emu.start()
            wait_until(lambda: dev.state == "ready", 10, f"ready again after restart {i}")
            assert dev.battery > 0
        assert settle(lambda: not hubwire_thread_ids() - threads0, 3), hubwire_threads()
        assert tty_fds() == fds0
        assert dev.session.stats.reboots == 3


def test_close_while_the_link_is_down_returns_promptly(emu: Emu) -> None:
    threads0, fds0 = hubwire_thread_ids(), tty_fds()
    dev = hubwire.connect(emu.link, cache_dir=False)
    emu.stop()
    wait_until(lambda: dev.state == "lost", 3, "link lost")
    t = time.monotonic()
    dev.close()
    assert time.monotonic() - t < 2.5
    assert settle(lambda: not hubwire_thread_ids() - threads0, 3), hubwire_threads()
    assert tty_fds() == fds0
