"""hubwire.diagnose: the messages for ports that cannot be opened, are busy, stay silent or chatter,
and the frame decoder's sample of what it discarded."""
from __future__ import annotations

import errno
import os
import pty
import subprocess
import sys
import tty

import pytest
import serial

from hubwire import diagnose
from hubwire.errors import InvalidValue, LinkLost, NakError, Timeout
from hubwire.wire.frame import NOISE_SAMPLE_SIZE, FrameDecoder, encode_frame

TEXT = b"Hello from setup()\r\ntemp=21.5\r\n"


# ------------------------------------------------------------------------ the decoder's sample

def test_decoder_keeps_the_first_discarded_bytes_only() -> None:
    d = FrameDecoder()
    good = encode_frame(0x48, 1, 0, b"abc")
    bad = bytearray(good)
    bad[2] ^= 0x40  # a corrupted byte: a CRC or COBS error
    frames = d.feed(good + bytes(bad) + good)
    assert len(frames) == 2 and d.crc + d.dropped == 1
    assert d.sample == bytes(bad)  # the discarded frame with its delimiter, not the good ones
    d.feed(b"x" * 40 + b"\x00" + b"y" * 40 + b"\x00")
    assert len(d.sample) == NOISE_SAMPLE_SIZE and d.sample.startswith(bytes(bad) + b"x" * 10)
    d.reset()
    assert len(d.sample) == NOISE_SAMPLE_SIZE  # kept, like the counters


def test_text_without_delimiters_shows_in_noise_not_in_counters() -> None:
    d = FrameDecoder()
    assert d.feed(TEXT) == [] and d.counters() == {"crc": 0, "overflow": 0, "dropped": 0}
    assert d.sample == b"" and d.noise() == TEXT
    d.feed(TEXT * 20)  # beyond the overflow limit: discarded, counted, sampled
    assert d.overflow == 0 and d.sample.startswith(TEXT) and len(d.noise()) == NOISE_SAMPLE_SIZE


def test_the_sample_changes_nothing_the_decoder_returns() -> None:
    stream = (encode_frame(1, 2, 3, b"x") + TEXT + b"\x00" + bytes(300) + encode_frame(4, 5, 6, b"yz")) * 3
    a, b = FrameDecoder(), FrameDecoder()
    whole = a.feed(stream)
    pieces = [f for i in range(0, len(stream), 7) for f in b.feed(stream[i:i + 7])]
    assert whole == pieces and len(whole) == 6
    assert a.counters() == b.counters() and a.sample == b.sample


# -------------------------------------------------------------------------- what was heard

def test_describe_noise_tells_text_from_bytes_and_stays_short() -> None:
    assert diagnose.describe_noise(TEXT) == ("text", '"Hello from setup() | temp=21.5"')
    kind, said = diagnose.describe_noise(b"A" * 64)
    assert kind == "text" and len(said) == diagnose.EXCERPT_CHARS + 2 and said.endswith('..."')
    assert diagnose.describe_noise(bytes([0x55, 0xAA, 0x00, 0xF1])) == ("bytes", "55 aa 00 f1")
    assert diagnose.describe_noise(bytes(range(128, 160)))[1].endswith(" ...")


def test_no_answer_message_silent_text_bytes_and_frames() -> None:
    zero = {"crc": 0, "overflow": 0, "dropped": 0}
    silent = diagnose.no_answer_message("/dev/ttyACM0", 5, zero, b"", hello_ms=100)
    assert silent == ("no Hubwire device answered on /dev/ttyACM0 within 5 s: the port stayed silent (nothing "
                      "arrived; a hello went out every 100 ms). Is the board plugged in, running a sketch that "
                      "uses Hubwire, and is this its port (`hubwire ports`)?")
    text = diagnose.no_answer_message("/dev/ttyACM0", 5, zero, TEXT)
    assert 'text arrived, is another sketch on the board? It said: "Hello from setup() | temp=21.5"' in text
    noise = diagnose.no_answer_message("/dev/ttyACM0", 2.5, {"crc": 0, "overflow": 0, "dropped": 3},
                                       bytes([0x55, 0xAA, 0x00]))
    assert "within 2.5 s: bytes that are not Hubwire frames arrived (55 aa 00)" in noise and "baud" in noise
    frames = diagnose.no_answer_message("/dev/ttyACM0", 5, {"crc": 2, "overflow": 0, "dropped": 0}, b"x", frames=4)
    assert "frames arrived but no handshake completed (4 valid, dropped: crc 2, overflow 0, dropped 0)" in frames


def test_a_real_pty_that_prints_text_is_described_as_text() -> None:
    """What the session does with what it reads, on a real port: decoder, then the message."""
    master, slave = pty.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)
    os.close(slave)
    port = serial.Serial(path, 115200, timeout=2)
    try:
        os.write(master, TEXT)
        d = FrameDecoder()
        d.feed(port.read(len(TEXT)))
    finally:
        port.close()
        os.close(master)
    msg = diagnose.no_answer_message(path, 1, d.counters(), d.noise(), frames=d.frames)
    assert msg.startswith(f"no Hubwire device answered on {path} within 1 s: text arrived, is another sketch")


# ---------------------------------------------------------------------------- opening a port

@pytest.mark.parametrize("code, kind", [(errno.EACCES, "PermissionDenied"), (errno.EBUSY, "PortBusy"),
                                        (errno.EAGAIN, "PortBusy"), (errno.ENOENT, "NoSuchPort"),
                                        (errno.EIO, "PortError")])
def test_open_error_kind(code: int, kind: str) -> None:
    exc = serial.SerialException(code, f"could not open port /dev/x: [Errno {code}]")
    assert diagnose.open_error_kind(exc) == kind
    err = diagnose.open_error("/dev/x", exc)
    assert err.kind == kind and err.errno == code and diagnose.error_type(err) == kind
    assert isinstance(err, OSError)  # the session's re-open loop keeps catching it


def test_windows_access_denied_is_a_busy_port() -> None:
    exc = serial.SerialException("could not open port 'COM3': PermissionError(13, 'Access is denied.', None, 5)")
    assert diagnose.open_error_kind(exc) == "PortBusy"


def test_permission_message_names_the_group_command_and_new_login(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    msg = diagnose.permission_message("/nonexistent/ttyACM0")
    assert msg == ("no permission to open /nonexistent/ttyACM0: serial ports belong to the 'dialout' group. "
                   "Join it with `sudo usermod -aG dialout $USER`, then log out and back in (a new login is "
                   "needed for the group to apply)")

    class Group:
        gr_mem = [diagnose.pwd.getpwuid(os.getuid()).pw_name]

    monkeypatch.setattr(diagnose.grp, "getgrnam", lambda name: Group)
    assert "you were added to the 'dialout' group after this login started" in \
        diagnose.permission_message("/nonexistent/ttyACM0")


# ------------------------------------------------------------------------------ who holds it

HOLD = "import os, sys; fd = os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY); print('held', flush=True); sys.stdin.read()"


def test_port_holders_finds_the_process_holding_a_pty() -> None:
    master, slave = pty.openpty()
    path = os.ttyname(slave)
    os.close(slave)
    p = subprocess.Popen([sys.executable, "-c", HOLD, path], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert p.stdout is not None and p.stdout.readline() == b"held\n"
        holders = diagnose.port_holders(path)
        assert [h.pid for h in holders] == [p.pid]
        assert holders[0].command.startswith(sys.executable + " -c import os")
        msg = diagnose.busy_message(path, holders)
        assert msg.startswith(f"{path} is in use by another program: pid {p.pid} ({sys.executable} -c ")
        assert f"`kill {p.pid}`" in msg
        assert diagnose.port_holders(path, exclude=[p.pid]) == []
    finally:
        p.communicate(b"")
    assert diagnose.port_holders(path) == []  # gone with the process
    os.close(master)


def test_port_holders_ignores_this_process_and_the_board_side_of_a_pty() -> None:
    # an emulator holds both ends of its pty: it is the board, not a second program
    board = ("import os, pty; m, s = pty.openpty(); print(os.ttyname(s), flush=True); "
             "import sys; sys.stdin.read()")
    p = subprocess.Popen([sys.executable, "-c", board], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert p.stdout is not None
        path = p.stdout.readline().decode().strip()
        mine = os.open(path, os.O_RDWR | os.O_NOCTTY)
        assert diagnose.port_holders(path) == []
        os.close(mine)
    finally:
        p.communicate(b"")
    assert diagnose.port_holders("socket://localhost:1") == [] and diagnose.port_holders(None) == []


def test_busy_message_without_visible_holders_says_how_to_find_them() -> None:
    assert diagnose.busy_message("/dev/ttyACM0", []) == (
        "/dev/ttyACM0 is in use by another program (not one of yours, or not visible: `sudo lsof /dev/ttyACM0` "
        "names it). Close it and try again; only one program at a time can talk to a board")


# ------------------------------------------------------------------------------ the CLI's words

def test_access_in_words_and_the_commands_that_apply() -> None:
    assert diagnose.access_words("rws") == "read, write, stream"
    assert diagnose.access_error("battery", "rs", "r") is None
    assert diagnose.access_error("battery", "rs", "w") == (
        "NotWritable", "channel 'battery' cannot be written: its access is read, stream; use `hubwire get` "
                       "or `hubwire watch`")
    assert diagnose.access_error("bumper", "e", "r") == (
        "NotReadable", "channel 'bumper' cannot be read: its access is event; use `hubwire watch`")
    assert diagnose.access_error("left", "rws", "c") == (
        "NotCallable", "channel 'left' cannot be called: its access is read, write, stream; use `hubwire get`, "
                       "`hubwire set` or `hubwire watch`")


def test_error_type_of_every_hub_error_is_listed() -> None:
    cases = {NakError(3, "left"): "Nak", InvalidValue("x", 2): "InvalidValue", Timeout("t"): "Timeout",
             LinkLost("l"): "LinkLost", ValueError("v"): "Error"}
    for exc, kind in cases.items():
        assert diagnose.error_type(exc) == kind and kind in diagnose.ERROR_TYPES
