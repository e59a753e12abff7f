"""Missions are not routed through `hubwire serve` yet: starting one through the service is a clear
error (sync, asyncio and the command line), and nothing reaches the board."""
from __future__ import annotations

import asyncio
import os

import pytest

import hubwire
import hubwire.aio
from hubwire.job import NOT_ROUTED

from missiondevice import DRIVE, MissionDevice

from .conftest import Serve


def test_starting_a_mission_through_the_service_is_a_clear_error(serve: Serve, boards_dir: str) -> None:
    with MissionDevice() as dev:
        os.symlink(dev.path, os.path.join(boards_dir, "rover"))
        serve.wait_state("rover", "ready")
        with hubwire.connect("rover") as rover:
            assert rover.url == "service:rover"
            with pytest.raises(hubwire.HubwireError) as e:
                rover.start("drive", 2.0)
            assert str(e.value) == NOT_ROUTED
            with pytest.raises(hubwire.HubwireError, match="not a mission"):
                rover.start("beep", 1)

        async def main() -> None:
            async with hubwire.aio.connect("rover") as arover:
                with pytest.raises(hubwire.HubwireError, match="not routed through the service"):
                    await arover.start("drive", 2.0)
        asyncio.run(main())
        r = serve.cli("call", "rover", "drive", "2", check=False)
        assert r.returncode == 1 and "missions are not routed through the service" in r.stderr
        assert dev.missions[DRIVE].starts == [] and dev.controls == 0
