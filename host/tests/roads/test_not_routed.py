"""What the routed road cannot do yet (hub channels a client declares) raises
:class:`hubwire.NotRoutedYet`, a :class:`hubwire.HubwireError` saying what to do, never AttributeError;
the same calls work on the direct road (tests/test_hub_connect.py)."""
from __future__ import annotations

from typing import Any, Callable, List

import pytest

import hubwire

from .conftest import Roads, aconnect, run

HUB_CALLS: List[Callable[[Any], Any]] = [
    lambda d: d.provide("tally", 1),
    lambda d: d.accept("tally", print, type="u32"),
    lambda d: d.action("bump", lambda x: x, type="u32", returns="u32"),
    lambda d: d.event("tick", type="u32"),
    lambda d: d.hub.provide("tally", 1),
    lambda d: d.hub_binding(),
]


def test_hub_declarations_say_they_are_not_routed(roads: Roads) -> None:
    with hubwire.connect(roads.target("routed", "soak"), timeout=10) as dev:
        assert len(dev.hub) == 0 and dev.notifications_pending == 0
        for i, call in enumerate(HUB_CALLS):
            with pytest.raises(hubwire.NotRoutedYet, match="hub channels a client declares .* are not routed through "
                               r"the service \(hubwire serve\) yet: declare them in a program that opens the "
                               "board's port itself"):
                call(dev)
        with pytest.raises(hubwire.InvalidValue):
            dev.start("count", -1)  # a bad goal is told before anything is sent, as on the direct road


def test_async_hub_declarations_say_they_are_not_routed(roads: Roads) -> None:
    async def main() -> None:
        async with aconnect(roads, "routed", "soak") as dev:
            assert len(dev.hub) == 0 and dev.notifications_pending == 0
            for call in HUB_CALLS:
                with pytest.raises(hubwire.NotRoutedYet, match="hub channels a client declares"):
                    call(dev)
    run(main())


def test_every_implementation_names_the_interface() -> None:
    from hubwire.aio import AsyncDevice
    from hubwire.board import BOARD_METHODS, AsyncBoardAPI, BoardAPI
    from hubwire.client.connection import AsyncRemoteDevice
    from hubwire.client.remote import RemoteDevice

    for cls, api in ((hubwire.Device, BoardAPI), (RemoteDevice, BoardAPI), (AsyncDevice, AsyncBoardAPI),
                     (AsyncRemoteDevice, AsyncBoardAPI)):
        assert api in cls.__mro__, cls  # so mypy checks its signatures against the interface
        missing = [m for m in BOARD_METHODS if not hasattr(cls, m)]
        assert not missing, (cls, missing)
