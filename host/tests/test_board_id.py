"""The board id (PROTOCOL.md 3.4): `R` on id 0 asks the device for the id that tells two boards
running one sketch apart; against the real library code in the emulator."""
import asyncio
import subprocess

import hubwire
import hubwire.aio
from hubwire.testing import tapped
from hubwire.wire.frame import decode_frame

from conftest import Emulator


def test_two_boards_running_one_sketch_report_their_own_ids(emulator_path, tmp_path, cache_dir):
    a = Emulator(emulator_path, str(tmp_path / "a"), ["--board-id", "0a1b2c3d"])
    b = Emulator(emulator_path, str(tmp_path / "b"), ["--board-id", "ff00ff00ff00ff00"])
    a.start()
    b.start()
    try:
        with hubwire.connect(transport=tapped(a.link), cache_dir=cache_dir) as da, \
                hubwire.connect(transport=tapped(b.link), cache_dir=cache_dir) as db:
            assert da.name == db.name == "rover"
            assert da.board_id() == "0a1b2c3d"
            assert db.board_id() == "ff00ff00ff00ff00"
    finally:
        a.stop()
        b.stop()


def test_a_board_without_an_id_reports_none_and_is_asked_once_per_boot(emulator, cache_dir):
    tap = tapped(emulator.link)
    asked = []

    def record(wire: bytes) -> bool:
        f = decode_frame(wire.strip(b"\x00"))
        if f is not None and f.type == ord("R") and f.id == 0:
            asked.append(f.seq)
        return True

    tap.tx_filter = record
    with hubwire.connect(transport=tap, cache_dir=cache_dir) as dev:
        assert dev.board_id() is None
        assert dev.board_id() is None  # remembered: no second question
        assert len(set(asked)) == 1  # one question (a retry keeps its seq)


def test_the_asyncio_device_reads_it_too(emulator_path, tmp_path, cache_dir):
    emu = Emulator(emulator_path, str(tmp_path / "c"), ["--board-id", "c0ffee"])
    emu.start()

    async def main() -> str:
        async with hubwire.aio.connect(emu.link, cache_dir=cache_dir) as dev:
            return await dev.board_id()

    try:
        assert asyncio.run(main()) == "c0ffee"
    finally:
        emu.stop()


def test_the_emulator_refuses_a_malformed_board_id(emulator_path, tmp_path):
    for bad in ["abc", "zz", "00" * 17, ""]:
        p = subprocess.run([emulator_path, "--link", str(tmp_path / "x"), "--board-id", bad],
                           capture_output=True, timeout=10)
        assert p.returncode == 2, bad
        assert b"--board-id HEX" in p.stderr
