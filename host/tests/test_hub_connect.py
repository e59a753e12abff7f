"""connect() and the hub channels a sketch expects: it raises naming what is missing unless the caller
provides them later; a Python ``int`` takes the integer type the device declares; an action handler
returning False refuses the call (NAK REJECTED) without an encoding warning. On the Soak sketch
(the C++ library, extras/tests/Soak: hub channels tally u32 written, bump u32(u32) called, tick u32
event) and on the scripted device of hubdevice.py (mode u8 event, target i16 written)."""
from __future__ import annotations

import logging
import os
import time
from typing import Any, Iterator, List

import pytest

import hubwire
from hubwire import HubChannelError, HubChannels, InvalidValue
from hubwire.testing import emulator_binary
from hubwire.wire.messages import NakCode

from conftest import Emulator
from hubdevice import HubDevice, connect


@pytest.fixture
def soak(tmp_path: Any) -> Iterator[Emulator]:
    path = os.path.join(os.path.dirname(emulator_binary()), "hubwire-soak-emulator")
    if not os.access(path, os.X_OK):
        pytest.fail(f"soak emulator not found at {path}: build it with `make emulator`", pytrace=False)
    emu = Emulator(path, str(tmp_path / "soak"))
    emu.start()
    yield emu
    emu.stop()


def _until(pred: Any, timeout: float = 10.0) -> Any:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        v = pred()
        if v:
            return v
        time.sleep(0.05)
    return pred()


def test_connect_without_the_hub_channels_raises_naming_them(soak: Emulator) -> None:
    with pytest.raises(HubChannelError) as e:
        hubwire.connect(soak.link, cache_dir=False, timeout=10)
    msg = str(e.value)
    for name in ("'tally'", "'bump'", "'tick'", "hub=hub", "hub_later=True"):
        assert name in msg, msg


def test_hub_later_connects_and_int_declared_later_takes_the_device_type(soak: Emulator) -> None:
    with hubwire.connect(soak.link, cache_dir=False, timeout=10, hub_later=True) as dev:
        assert dev.hub_binding() == {"tally": "UNKNOWN_CHANNEL", "bump": "UNKNOWN_CHANNEL", "tick": "UNKNOWN_CHANNEL"}
        tallies: List[int] = []

        def tally(v: int) -> None:
            tallies.append(v)
        dev.accept("tally", tally)  # int: the device's u32, no type= needed

        @dev.action("bump")
        def bump(x: int) -> int:
            return x + 1
        dev.event("tick", type=int)
        assert dev.hub_binding() == {"tally": "ok", "bump": "ok", "tick": "ok"}
        assert dev.hub["bump"].channel.type_name == "(u32) -> u32" and dev.hub["tick"].channel.type_name == "u32"
        dev.hub_load = 1
        assert _until(lambda: dev.bump_ok >= 2), "the board's calls of bump were not answered"
        dev.hub_load = 0
        assert dev.bump_wrong == 0 and dev.bump_failed == 0 and tallies


def test_int_takes_the_integer_type_the_device_declares() -> None:
    hub = HubChannels()
    hub.provide("setpoint", 21.5)
    hub.accept("report", type="struct", fields={"temp": "f32", "heater": "bool"})
    hub.action("dock", lambda speed: True, type=float, returns=bool)
    hub.event("mode", type=int)  # the device takes u8

    @hub.accept("target", min=-100, max=100)
    def target(v: int) -> None:  # the device writes i16
        pass
    with HubDevice() as dev, connect(dev, hub=hub) as d:
        assert d.hub["mode"].channel.type_name == "u8" and d.hub["target"].channel.type_name == "i16"
        assert d.hub_binding() == dict.fromkeys(("setpoint", "report", "dock", "mode", "target"), "ok")
        with pytest.raises(InvalidValue):
            d.notify("mode", 300)  # checked against u8
        d.notify("mode", 3)


def test_action_returning_false_is_rejected_without_a_warning(soak: Emulator,
                                                              caplog: pytest.LogCaptureFixture) -> None:
    hub = HubChannels()
    hub.accept("tally", type="u32")
    hub.action("bump", lambda x: False, type="u32", returns="u32")  # refuses every call
    hub.event("tick", type="u32")
    with caplog.at_level(logging.WARNING, logger="hubwire"):
        with hubwire.connect(soak.link, cache_dir=False, timeout=10, hub=hub) as dev:
            dev.hub_load = 1
            assert _until(lambda: dev.bump_failed >= 2), "the board's calls of bump were not refused"
            dev.hub_load = 0
            assert dev.last_hub_failure == NakCode.REJECTED and dev.bump_ok == 0 and dev.bump_wrong == 0
    assert not [r for r in caplog.records if "bump" in r.getMessage()], [r.getMessage() for r in caplog.records]
