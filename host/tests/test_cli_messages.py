"""What the ``hubwire`` command says when something is wrong, run as a user runs it (a subprocess):
against the emulator where a device is needed, against plain ptys for silent, chattering, busy and
forbidden ports."""
from __future__ import annotations

import json
import os
import pty
import signal
import subprocess
import sys
import threading
import time
import tty
from typing import Any, Dict, Iterator, List, Optional, Tuple

import pytest
from conftest import Emulator

from hubwire.diagnose import ERROR_TYPES

CLI = [sys.executable, "-m", "hubwire"]


def run(*args: str, cache: Optional[str] = None, timeout: float = 30) -> subprocess.CompletedProcess:
    env = dict(os.environ, HUBWIRE_CACHE_DIR=cache or os.devnull)
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=timeout, env=env)


def json_error(r: subprocess.CompletedProcess) -> Dict[str, Any]:
    """The one JSON error a failed ``--json`` command printed: on stdout, nothing on stderr."""
    assert r.returncode == 1 and r.stderr == "", r.stderr
    lines = r.stdout.splitlines()
    assert len(lines) == 1, r.stdout
    err = json.loads(lines[0])
    assert err["error"] in ERROR_TYPES
    return err  # type: ignore[no-any-return]


class Port:
    """A pty whose board side this test plays: silent, or writing ``chatter`` every 50 ms."""

    def __init__(self, chatter: bytes = b"") -> None:
        self.master, slave = pty.openpty()
        tty.setraw(slave)  # as a real serial port: no echo, no line editing
        self.path = os.ttyname(slave)
        os.close(slave)
        os.set_blocking(self.master, False)  # chatter nobody reads is dropped, as a board's is
        self.chatter = chatter
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        import select

        while not self._stop.is_set():
            if self.chatter:
                try:
                    os.write(self.master, self.chatter)
                except OSError:
                    pass
            if select.select([self.master], [], [], 0.05)[0]:
                try:
                    os.read(self.master, 4096)  # what the hub sends: hellos, unanswered
                except OSError:
                    pass

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)
        os.close(self.master)


@pytest.fixture
def port() -> Iterator[Port]:
    p = Port()
    yield p
    p.close()


@pytest.fixture
def chatty_port() -> Iterator[Port]:
    p = Port(b"Hello from setup()\r\ntemp=21.5\r\n")
    yield p
    p.close()


# --------------------------------------------------------------------------- opening a port

# The command as user nobody, every module it may import loaded first: nobody may not be able to
# read the clone (root's home is 0700), and an import after the switch would fail for that reason.
AS_NOBODY = """
import importlib, os, pkgutil, sys
import hubwire, hubwire.cli, serial.serialposix
assert hubwire.__file__.startswith(sys.argv[1]), hubwire.__file__
for m in pkgutil.walk_packages(hubwire.__path__, "hubwire.", onerror=lambda name: None):
    if not m.name.startswith(("hubwire.dashboard", "hubwire.__main__")):
        try:
            importlib.import_module(m.name)
        except ImportError:
            pass  # an optional extra that is not installed: the command does not use it
hubwire.cli.build_parser().parse_args(sys.argv[2:])
os.setgroups([]); os.setgid(65534); os.setuid(65534)
sys.exit(hubwire.cli.main(sys.argv[2:]))
"""

@pytest.fixture(params=["here", "private"])
def package_path(request: Any, tmp_path: Any) -> Optional[str]:
    """Where the child imports hubwire from: this checkout, or a copy in a folder only its owner can
    enter (a clone in root's home, mode 0700), so the result cannot depend on where the clone lives."""
    if request.param == "here":
        return None
    import shutil

    import hubwire

    private = tmp_path / "private"
    shutil.copytree(os.path.dirname(hubwire.__file__), private / "hubwire",
                    ignore=shutil.ignore_patterns("__pycache__"))
    os.chmod(private, 0o700)
    return str(private)


def test_no_permission_says_to_join_dialout(port: Port, package_path: Optional[str]) -> None:
    env = dict(os.environ)
    if package_path is not None:
        env["PYTHONPATH"] = package_path
    if os.geteuid() == 0:
        # root opens anything: run the command as nobody, with every module it may use loaded first
        # (nobody cannot read a clone in root's home)
        code = AS_NOBODY
        cmd = [sys.executable, "-c", code, package_path or os.path.dirname(os.path.dirname(__file__))]
    else:
        os.chmod(port.path, 0)
        cmd = CLI
    r = subprocess.run([*cmd, "info", port.path, "--no-cache"], capture_output=True, text=True, timeout=30,
                       env=env)
    assert r.returncode == 1
    assert r.stderr == (f"hubwire: no permission to open {port.path}: serial ports belong to the 'dialout' "
                        "group. Join it with `sudo usermod -aG dialout $USER`, then log out and back in (a new "
                        "login is needed for the group to apply)\n")
    r = subprocess.run([*cmd, "info", port.path, "--no-cache", "--json"], capture_output=True, text=True, timeout=30,
                       env=env)
    assert json_error(r)["error"] == "PermissionDenied"


def test_a_port_that_does_not_exist() -> None:
    r = run("get", "/dev/nonexistent-hubwire-port", "battery")
    assert r.returncode == 1 and r.stderr == (
        "hubwire: there is no serial port /dev/nonexistent-hubwire-port: is the board plugged in? "
        "`hubwire ports` lists the ports there are\n")
    assert json_error(run("get", "/dev/nonexistent-hubwire-port", "battery", "--json"))["error"] == "NoSuchPort"


def test_a_port_held_by_another_program_names_it(port: Port) -> None:
    hold = "import os, sys; fd = os.open(sys.argv[1], os.O_RDWR | os.O_NOCTTY); print('held', flush=True); sys.stdin.read()"
    holder = subprocess.Popen([sys.executable, "-c", hold, port.path], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert holder.stdout is not None and holder.stdout.readline() == b"held\n"
        r = run("info", port.path, "--timeout", "1")
        assert r.returncode == 1
        assert r.stderr.startswith(f"hubwire: {port.path} is in use by another program: pid {holder.pid} "
                                   f"({sys.executable} -c import os, sys;")
        assert r.stderr.endswith(f". Close it (or `kill {holder.pid}`) and try again; only one program at a time "
                                 "can talk to a board\n")
        err = json_error(run("info", port.path, "--timeout", "1", "--json"))
        assert err["error"] == "PortBusy" and f"pid {holder.pid}" in err["message"]
    finally:
        holder.communicate(b"", timeout=10)


# ------------------------------------------------------------------- silent and chattering ports

def test_a_silent_port_is_a_connect_timeout(port: Port) -> None:
    r = run("info", port.path, "--timeout", "1")
    assert r.returncode == 1 and r.stderr.startswith(f"hubwire: no Hubwire device answered on {port.path} within 1 s")
    assert json_error(run("info", port.path, "--timeout", "1", "--json"))["error"] == "ConnectTimeout"


# These two need the session to build its connect-timeout message with diagnose.no_answer_message
# (the decoder's counters and noise()); until it does they fail, and strict=True flags the day they pass.
def test_a_silent_port_says_it_stayed_silent(port: Port) -> None:
    r = run("info", port.path, "--timeout", "1")
    assert r.stderr.startswith(f"hubwire: no Hubwire device answered on {port.path} within 1 s: the port stayed "
                               "silent (nothing arrived; a hello went out every 100 ms)")


def test_a_chattering_port_says_what_it_heard(chatty_port: Port) -> None:
    r = run("info", chatty_port.path, "--timeout", "1")
    head = (f"hubwire: no Hubwire device answered on {chatty_port.path} within 1 s: text arrived, is another "
            'sketch on the board? It said: "')
    assert r.stderr.startswith(head), r.stderr
    said = r.stderr[len(head):].split('"')[0]  # where it starts depends on when the port was opened
    assert "temp=21.5 | " in said and "Hello from s" in said and len(said) <= 48


# ---------------------------------------------------------------------------------- channels

def test_access_errors_are_in_words(emulator: Emulator, cache_dir: str) -> None:
    cases: List[Tuple[Tuple[str, ...], str, str]] = [
        (("get", "bumper"), "NotReadable", "channel 'bumper' cannot be read: its access is event; use `hubwire watch`"),
        (("set", "battery", "3"), "NotWritable",
         "channel 'battery' cannot be written: its access is read, stream; use `hubwire get` or `hubwire watch`"),
        (("call", "left", "1"), "NotCallable", "channel 'left' cannot be called: its access is read, write, "
                                               "stream; use `hubwire get`, `hubwire set` or `hubwire watch`"),
    ]
    for args, kind, message in cases:
        r = run(args[0], emulator.link, *args[1:], cache=cache_dir)
        assert r.returncode == 1 and r.stderr == f"hubwire: {message}\n" and r.stdout == ""
        assert json_error(run(args[0], emulator.link, *args[1:], "--json", cache=cache_dir)) == \
            {"error": kind, "message": message}


def test_every_json_error_has_a_stable_type_and_is_printed_once(emulator: Emulator, cache_dir: str) -> None:
    cases = [(("get", "nope"), "UnknownChannel"), (("set", "led", "maybe"), "InvalidValue"),
             (("set", "left", "3"), "InvalidValue"), (("call", "beep"), "InvalidValue"),
             (("call", "beep", "100", "--timeout", "x"), "Usage")]
    for args, kind in cases:
        r = run(args[0], emulator.link, *args[1:], "--json", cache=cache_dir)
        if kind == "Usage":
            assert r.returncode == 2 and r.stderr == "" and json.loads(r.stdout)["error"] == "Usage"
            continue
        assert json_error(r)["error"] == kind, args
    err = json_error(run("get", emulator.link, "nope", "--json", cache=cache_dir))
    assert err["message"].startswith("rover has no channel 'nope'; channels: left, right, imu")
    assert run("call", emulator.link, "beep", cache=cache_dir).stderr == "hubwire: beep needs an argument (u16)\n"


def test_set_warns_that_a_failsafe_value_comes_back(emulator: Emulator, cache_dir: str) -> None:
    warning = ("left has a failsafe value (0): the board sets it back from 0.5 to 0 about a second after this "
               "command's connection ends, when it sees the link lost; to hold 0.5, keep a program connected "
               "(hubwire.connect in Python)")
    r = run("set", emulator.link, "left", "0.5", cache=cache_dir)
    assert r.returncode == 0 and r.stdout == "" and r.stderr == f"hubwire: warning: {warning}\n"
    r = run("set", emulator.link, "left", "0.5", "--json", cache=cache_dir)
    assert r.returncode == 0 and r.stderr == ""
    assert json.loads(r.stdout) == {"channel": "left", "value": 0.5, "ok": True, "warning": warning}
    r = run("set", emulator.link, "name", "robbie", cache=cache_dir)
    assert r.returncode == 0 and r.stderr == ""  # no failsafe, no warning
    # and it is true: with no hub for 4 hub heartbeats (4 x 250 ms) the board applies the failsafe; each
    # `get` is a hub too, so leave the board alone for longer than that between them
    quiet = 1.5 * 4 * 0.25
    deadline = time.monotonic() + 20
    while True:
        time.sleep(quiet)
        r = run("get", emulator.link, "left", cache=cache_dir)
        if r.stdout.strip() == "0":
            break
        assert r.stdout.strip() == "0.5" and time.monotonic() < deadline, "left never went back to its failsafe"


# ----------------------------------------------------------------------------------- help

def test_help_lists_bool_words_positionals_and_only_options_that_apply() -> None:
    env = dict(os.environ, COLUMNS="200")
    helps = {c: subprocess.run([*CLI, c, "--help"], capture_output=True, text=True, env=env).stdout
             for c in ("ports", "info", "get", "set", "call", "watch")}
    assert "true/false, 1/0, on/off, yes/no" in helps["set"]
    assert "--json" in helps["ports"]
    assert all(o not in helps["ports"] for o in ("--baud", "--timeout", "--no-cache"))
    for cmd, text in helps.items():
        positional = text.split("positional arguments:")[1].split("options:")[0] if cmd != "ports" else ""
        for line in positional.splitlines()[1:]:
            if line.strip():
                assert len(line.split()) > 1, f"{cmd}: positional without help: {line!r}"
    assert "action " in helps["call"] and "arg " in helps["call"] and "channel " in helps["get"]
    top = subprocess.run([*CLI, "--help"], capture_output=True, text=True, env=env).stdout
    assert all(f"  {k} " in top for k in ERROR_TYPES)


# ------------------------------------------------------------------------------ closed pipes

def test_head_ends_the_output_quietly(emulator: Emulator, cache_dir: str) -> None:
    env = dict(os.environ, HUBWIRE_CACHE_DIR=cache_dir)
    cmd = " ".join([*CLI, "info", emulator.link]) + " | head -2"
    r = subprocess.run(["bash", "-o", "pipefail", "-c", cmd], capture_output=True, text=True, env=env, timeout=30)
    assert r.returncode in (0, 141) and r.stderr == "" and len(r.stdout.splitlines()) == 2


@pytest.mark.parametrize("args", [("info",), ("watch", "--json", "--duration", "20")])
def test_a_reader_gone_before_output_means_status_141_and_no_traceback(
        emulator: Emulator, cache_dir: str, args: Tuple[str, ...]) -> None:
    env = dict(os.environ, HUBWIRE_CACHE_DIR=cache_dir)
    p = subprocess.Popen([*CLI, args[0], emulator.link, *args[1:]], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         env=env)
    assert p.stdout is not None and p.stderr is not None
    p.stdout.close()  # the reader goes away before the command has connected
    err = p.stderr.read()
    assert p.wait(30) == 141 and err == b""


# -------------------------------------------------------------------------------- watch

def watch(link: str, cache: str, *args: str) -> subprocess.Popen:
    env = dict(os.environ, HUBWIRE_CACHE_DIR=cache)
    return subprocess.Popen([*CLI, "watch", link, "--rate", "4", "--timeout", "1", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)


def lines_until(p: subprocess.Popen, predicate: Any) -> List[str]:
    assert p.stdout is not None
    seen: List[str] = []
    for line in p.stdout:
        seen.append(line)
        if predicate(line):
            return seen
    raise AssertionError(f"watch ended without the line expected; it printed {seen[-4:]}")


def test_watch_ends_with_an_error_when_the_board_vanishes(emulator: Emulator, cache_dir: str) -> None:
    p = watch(emulator.link, cache_dir, "--duration", "60")
    lines_until(p, lambda ln: "link state=ready" in ln)
    emulator.stop()  # unplugged: the port goes away
    out, err = p.communicate(timeout=30)
    assert p.returncode == 1 and "link state=lost" in out
    assert err == (f"hubwire: the board on {emulator.link} vanished: the link is down and it did not come back "
                   "within 1 s (--timeout); pass --wait to keep watching until it returns\n")


def test_watch_json_reports_a_silent_board_as_link_lost(emulator: Emulator, cache_dir: str) -> None:
    p = watch(emulator.link, cache_dir, "--duration", "60", "--json")
    lines_until(p, lambda ln: '"state": "ready"' in ln)
    emulator.pause()  # still plugged in, but silent
    try:
        out, err = p.communicate(timeout=30)
    finally:
        emulator.resume()
    last = json.loads(out.splitlines()[-1])
    assert p.returncode == 1 and err == "" and last["error"] == "LinkLost" and "vanished" in last["message"]


def test_watch_wait_rides_through_the_board_going_away(emulator: Emulator, cache_dir: str) -> None:
    p = watch(emulator.link, cache_dir, "--duration", "60", "--json", "--wait")
    try:
        lines_until(p, lambda ln: '"state": "ready"' in ln)
        emulator.pause()
        down = lines_until(p, lambda ln: '"link"' in ln and '"state": "ready"' not in ln)
        t0 = json.loads(down[-1])["t"]
        # gone for longer than --timeout: without --wait the command would have ended by now
        lines_until(p, lambda ln: '"link"' in ln and json.loads(ln)["t"] > t0 + 1.5)
        emulator.resume()
        lines_until(p, lambda ln: '"state": "ready"' in ln)
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=20)
    finally:
        emulator.resume()
        if p.poll() is None:
            p.kill()
    assert p.returncode == 0 and err == ""


def test_watch_wait_waits_for_a_port_to_appear(emulator: Emulator, cache_dir: str) -> None:
    missing = emulator.link + "-later"
    p = watch(missing, cache_dir, "--duration", "60", "--wait")
    try:
        assert p.stderr is not None
        first = p.stderr.readline()
        assert first.startswith(f"hubwire: waiting for a board on {missing} (there is no serial port {missing}")
        os.symlink(os.path.realpath(emulator.link), missing)
        lines_until(p, lambda ln: "link state=ready" in ln)
        p.send_signal(signal.SIGINT)
        p.communicate(timeout=20)
    finally:
        if p.poll() is None:
            p.kill()
        os.unlink(missing)
    assert p.returncode == 0
