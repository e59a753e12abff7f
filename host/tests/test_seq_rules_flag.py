"""The hello flag SEQ_RULES (PROTOCOL.md 3.1, 4.1): both reference sides set it, and the hub says
plainly when a board's library predates the sequence rules, whose messages may be lost in some
traffic mixes, instead of letting it pass in silence."""
from __future__ import annotations

import logging
from typing import Any

import hubwire
from hubwire.wire import messages as m
from fakedevice import FakeDevice

WARNING = "older than its sequence rules"


class OldDevice(FakeDevice):
    """The fake device as a board built with a library before the sequence rules announces itself."""

    def _hello(self, reply: bool) -> None:
        flags = m.FLAG_DEVICE | (m.FLAG_REPLY if reply else 0)
        h = m.Hello(self.version, flags, 0x1234567, self.max_payload, 250, self.hash, len(self.descriptor),
                    digest=self.digest)
        self._send(m.HELLO, 0, 0, h.pack())


def test_a_board_without_the_flag_is_named_once(cache_dir: str, caplog: Any) -> None:
    caplog.set_level(logging.WARNING, logger="hubwire")
    with OldDevice() as fake, hubwire.connect(fake.path, cache_dir=cache_dir) as dev:
        dev.read("x")
        dev.read("x")
    lines = [r.getMessage() for r in caplog.records if WARNING in r.getMessage()]
    assert len(lines) == 1 and fake.path in lines[0] and "build the sketch again" in lines[0]


def test_a_board_with_the_flag_is_not(cache_dir: str, caplog: Any) -> None:
    caplog.set_level(logging.WARNING, logger="hubwire")
    with FakeDevice() as fake, hubwire.connect(fake.path, cache_dir=cache_dir) as dev:
        dev.read("x")
    assert not [r for r in caplog.records if WARNING in r.getMessage()]


def test_the_library_sets_it_and_the_hub_too(emulator: Any, caplog: Any) -> None:
    caplog.set_level(logging.WARNING, logger="hubwire")
    with hubwire.connect(emulator.link, cache_dir=False) as dev:
        assert dev.session.core.link.device_hello.flags & m.FLAG_SEQ_RULES
        dev.read("left")
    assert not [r for r in caplog.records if WARNING in r.getMessage()]
