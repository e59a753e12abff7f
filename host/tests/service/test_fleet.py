"""The Fleet in this process: boards told apart by the USB serial number of their port, keys that
follow a board across a replug on another port, and the changes consumers are told about. The USB
scan is given ports as pyserial's list_ports would (a known vendor id and a serial number) whose
device paths are the emulators' ptys."""
from __future__ import annotations

import asyncio
from typing import Any, Callable, Dict, List, Optional

from conftest import Emulator
from hubwire.daemon.fleet import Board, Changes, Fleet, UnknownBoard


class UsbPort:
    """What ``serial.tools.list_ports.comports()`` gives for a USB board."""

    def __init__(self, device: str, serial_number: Optional[str]) -> None:
        self.device = device
        self.serial_number = serial_number
        self.vid, self.pid = 0x2341, 0x0043  # an Arduino Uno


async def until(changes: Changes, seen: List[Board], want: Callable[[Board], bool],
                timeout: float = 20.0) -> Board:
    """The next change that ``want``s (every change on the way is kept in ``seen``)."""
    async def find() -> Board:
        async for b in changes:
            seen.append(b)
            if want(b):
                return b
        raise AssertionError("changes ended")
    return await asyncio.wait_for(find(), timeout)


def test_usb_serial_numbers_tell_boards_apart_and_follow_a_replug(emulators: Callable[[str], Emulator],
                                                                  tmp_path: Any) -> None:
    usb: List[UsbPort] = []

    async def main() -> None:
        fleet = Fleet(usb=True, lister=lambda: list(usb), poll_interval=0.1, udev=False,
                      cache_dir=str(tmp_path / "cache"))
        changes = fleet.changes()
        seen: List[Board] = []
        await fleet.start()
        a = emulators("a")
        usb.append(UsbPort(a.link, "SN-A"))
        await until(changes, seen, lambda b: b.key == "rover--SN-A" and b.state == "ready")
        b = emulators("b")
        usb.append(UsbPort(b.link, "SN-B"))
        got = await until(changes, seen, lambda b: b.key == "rover--SN-B" and b.state == "ready")
        assert (got.name, got.board_id, got.port, got.attached) == ("rover", "SN-B", b.link, 1)
        assert fleet.get("rover--SN-A").board_id == "SN-A"
        assert fleet.resolve("rover-SN-A").key == "rover--SN-A"  # name-<board id> always reaches a board
        assert fleet.resolve(b.link).key == "rover--SN-B"   # and so does its port
        old_dev = got.device
        assert old_dev is not None and await old_dev.read("battery") > 0

        b.stop()  # unplug: the port goes away
        usb.pop()
        gone = await until(changes, seen, lambda x: x.key == "rover--SN-B" and x.state == "unplugged")
        assert gone.port is None and gone.device is None
        c = emulators("c")  # replugged: another port name, the same serial number
        usb.append(UsbPort(c.link, "SN-B"))
        back = await until(changes, seen, lambda x: x.key == "rover--SN-B" and x.state == "ready")
        assert (back.port, back.attached) == (c.link, 2)
        assert back.device is not None and back.device is not old_dev
        await back.device.write("left", 0.5)
        assert await fleet.get("rover--SN-B").device.read("left") == 0.5  # type: ignore[union-attr]
        assert await fleet.get("rover--SN-A").device.read("left") == 0.0  # type: ignore[union-attr]

        assert [x.key for x in fleet.boards()] == ["rover--SN-A", "rover--SN-B"]
        states = [(x.state, x.port) for x in seen if x.key == "rover--SN-B"]
        # (the link may be seen lost, the port failing, before the scan sees the port gone)
        assert [st for st in states if st != ("lost", b.link)] == [
            ("ready", b.link), ("unplugged", None), ("ready", c.link)]
        try:
            fleet.get("nope")
            raise AssertionError("no UnknownBoard")
        except UnknownBoard as e:
            assert isinstance(e, KeyError) and "rover--SN-A (ready)" in str(e) and "rover--SN-B (ready)" in str(e)
        await changes.aclose()
        await fleet.close()
        assert all(x.device is None or x.device.state == "closed" for x in fleet.boards())
    asyncio.run(main())


def test_a_port_that_is_no_hubwire_board_is_left_alone(tmp_path: Any) -> None:
    """A port that never answers is tried again later with a growing pause, and never becomes a board."""
    import os
    import pty

    master, slave = pty.openpty()
    path = os.ttyname(slave)

    async def main() -> None:
        fleet = Fleet(usb=False, ports=[path], poll_interval=0.05, udev=False, connect_timeout=0.3)
        await fleet.start()
        try:
            for _ in range(100):
                await asyncio.sleep(0.05)
                a = fleet._attempts.get(os.path.realpath(path))
                if a is not None and a.failures >= 2:
                    break
            assert a is not None and a.failures == 2  # the second pause (2 s) is not over yet
            assert fleet.boards() == []
        finally:
            await fleet.close()
    try:
        asyncio.run(main())
    finally:
        os.close(master)
        os.close(slave)


def test_board_ids_the_devices_report_keep_their_keys_when_replugged_swapped(
        emulators: Callable[..., Emulator], boards_dir: str, tmp_path: Any) -> None:
    """No USB serial number (ptys): the board id each device reports (R on id 0) is its identity,
    so two boards running one sketch unplugged and plugged back the other way round keep their keys."""
    async def main() -> None:
        fleet = Fleet(globs=[boards_dir + "/*"], usb=False, poll_interval=0.1, udev=False,
                      cache_dir=str(tmp_path / "cache"))
        changes = fleet.changes()
        seen: List[Board] = []
        await fleet.start()
        a = emulators("p1", "--board-id", "aa01")
        await until(changes, seen, lambda b: b.board_id == "aa01" and b.state == "ready")
        b = emulators("p2", "--board-id", "bb02")
        await until(changes, seen, lambda b: b.board_id == "bb02" and b.state == "ready")
        keys = {x.board_id: x.key for x in fleet.boards()}
        assert keys == {"aa01": "rover--aa01", "bb02": "rover--bb02"}
        a.stop()
        b.stop()
        await until(changes, seen, lambda _: all(x.state == "unplugged" for x in fleet.boards()))
        emulators("p3", "--board-id", "bb02")  # back the other way round, on new ports
        emulators("p4", "--board-id", "aa01")
        await until(changes, seen, lambda _: all(x.state == "ready" for x in fleet.boards()))
        assert {x.board_id: x.key for x in fleet.boards()} == keys
        assert fleet.get("rover--bb02").port is not None and fleet.get("rover--bb02").port.endswith("p3")
        assert fleet.get("rover--aa01").port is not None and fleet.get("rover--aa01").port.endswith("p4")
        await changes.aclose()
        await fleet.close()
    asyncio.run(main())


def test_a_restart_finding_the_boards_in_another_order_gives_each_its_key(
        emulators: Callable[..., Emulator], boards_dir: str, tmp_path: Any) -> None:
    """Keys come from the board (name and id), not from which board a scan finds first: a service
    restarted with the boards found the other way round gives each board the key it had."""
    async def run(first: str, second: str) -> Dict[Optional[str], str]:
        fleet = Fleet(globs=[boards_dir + "/*"], usb=False, poll_interval=0.1, udev=False,
                      cache_dir=str(tmp_path / "cache"))
        changes = fleet.changes()
        seen: List[Board] = []
        await fleet.start()
        emus = [emulators(f"{first}-0", "--board-id", first)]
        await until(changes, seen, lambda b: b.board_id == first and b.state == "ready")
        emus.append(emulators(f"{second}-0", "--board-id", second))
        await until(changes, seen, lambda b: b.board_id == second and b.state == "ready")
        keys = {x.board_id: x.key for x in fleet.boards()}
        await changes.aclose()
        await fleet.close()
        for e in emus:
            e.stop()
        return keys

    before = asyncio.run(run("aa01", "bb02"))
    after = asyncio.run(run("bb02", "aa01"))
    assert before == after == {"aa01": "rover--aa01", "bb02": "rover--bb02"}
