"""Hints for the commonest sketch mistakes, from what the hub hears: a loop() blocked by delay()
(the device's heartbeats and answers come seconds apart) and debug text printed on the hub's line."""
from __future__ import annotations

import logging
import os
import signal
import subprocess
import sys
import time
from typing import Any, Iterator

import pytest

import hubwire

from hubdevice import HubDevice, connect, wait_for

BLOCKED_S = 1.5  # as delay(1500) in loop(): the device reads and answers once per pass


class BlockedDevice(HubDevice):
    """A device whose loop() waits BLOCKED_S per pass once linked; it says so in its heartbeats."""

    def __init__(self) -> None:
        super().__init__(beat_ms=int(BLOCKED_S * 1000))

    def tick(self) -> None:
        if self.linked:
            time.sleep(BLOCKED_S)


@pytest.fixture
def blocked() -> Iterator[HubDevice]:
    d = BlockedDevice()
    d.start()
    yield d
    d.close()


def test_a_blocked_loop_is_named_when_the_link_fails(blocked: HubDevice) -> None:
    start = time.monotonic()
    with pytest.raises((hubwire.LinkLost, hubwire.Timeout)) as e:
        with connect(blocked) as board:
            for _ in range(10):
                board.health()
                board.read("temp")
    assert "the board's loop() seems blocked (" in str(e.value), str(e.value)
    assert "declared 250 ms): avoid delay() in loop()" in str(e.value)
    # the connect deadline (5 s) from the first loss, plus the time to get there: not much more
    assert time.monotonic() - start < 5 + 4 * BLOCKED_S + 5


def test_a_board_that_goes_silent_is_not_called_blocked() -> None:
    with HubDevice() as dev:
        with connect(dev) as board:
            dev.mute = True  # unplugged, or reset and held in its bootloader
            with pytest.raises((hubwire.LinkLost, hubwire.Timeout)) as e:
                for _ in range(50):
                    board.read("temp")
                    time.sleep(0.1)
    assert "loop()" not in str(e.value), str(e.value)


# ------------------------------------------------------------------------- Serial.println text

def say(dev: HubDevice, text: bytes) -> None:
    """The sketch prints ``text`` on the Hubwire line, between its frames."""
    with dev.lock:
        os.write(dev.master, text)


def test_printed_text_is_shown_once_then_counted(caplog: Any) -> None:
    caplog.set_level(logging.WARNING, logger="hubwire")
    with HubDevice() as dev:
        with connect(dev) as board:
            for n in range(3):
                say(dev, b"temp=21.5\r\n")
                wait_for(lambda: board.session.printed()[0] == n + 1)
            count, lines = board.session.printed()
    assert count == 3 and lines == ["temp=21.5"] * 3
    said = [r.getMessage() for r in caplog.records if "printed" in r.getMessage()]
    assert said == [f"hubwire: the board on {dev.path} printed: 'temp=21.5' (text on the Hubwire line spoils the "
                    "frame after it: print on another port, or not at all)"]  # then not again for 30 s


def test_printed_text_is_bounded_and_printable_only() -> None:
    from hubwire.wire.frame import TEXT_CHARS, TEXT_LINES, FrameDecoder

    d = FrameDecoder()
    d.feed(b"\xff\xfe\x1b[2Jbad\x07\n" + b"x" * 500 + b"\n" + b"".join(b"line %d\r\n" % i for i in range(20)) + b"\x00")
    assert d.text_lines == 21  # the line with control characters is not text
    assert len(d.text) == TEXT_LINES and list(d.text)[-1] == "line 19"
    assert all(len(t) <= TEXT_CHARS and t.isprintable() for t in d.text)


def test_watch_shows_what_the_board_printed() -> None:
    with HubDevice() as dev:
        watch = subprocess.Popen([sys.executable, "-m", "hubwire", "watch", dev.path, "--duration", "30",
                                  "--no-cache"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                 env=dict(os.environ, HUBWIRE_NO_SERVICE="1"))
        try:
            assert watch.stdout is not None
            first = watch.stdout.readline()
            assert first.startswith("t="), first + watch.stderr.read() if watch.stderr else ""
            deadline = time.monotonic() + 20
            seen = ""
            while "the board printed: hello from loop()" not in seen and time.monotonic() < deadline:
                say(dev, b"hello from loop()\n")
                seen += watch.stdout.readline()
            assert "the board printed: hello from loop()" in seen
        finally:
            watch.send_signal(signal.SIGINT)
            watch.communicate(timeout=30)
