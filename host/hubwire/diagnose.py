"""What went wrong on a port, in words that say what to do: the messages of the ``hubwire`` command
and of :func:`hubwire.connect` for ports that cannot be opened, are busy, stay silent or send
something other than Hubwire frames.

Everything here is a function of its arguments, except :func:`port_holders` (reads ``/proc``) and
:func:`permission_message` (reads the port's owner group), so each message can be tested alone.
"""
from __future__ import annotations

import errno
import os
import stat

try:  # imported here, not when needed: a process that dropped its privileges may not read them then
    import grp
    import pwd
except ImportError:  # pragma: no cover - Windows has no permission groups to explain
    grp = pwd = None  # type: ignore[assignment]
from typing import List, Mapping, NamedTuple, Optional, Sequence, Tuple

from .errors import ERROR_TYPES, HubwireError, error_type

__all__ = [
    "ACCESS_WORDS", "ERROR_TYPES", "Holder", "PortOpenError", "access_error", "access_words", "busy_message",
    "RESTART_NOTE", "blocked_loop_hint", "describe_noise", "error_type", "failsafe_warning", "install_hint", "local_path", "no_answer_message", "open_error",
    "open_error_kind", "open_error_message", "permission_message", "port_holders",
]

#: access letters in words, the command that uses each, and what lacking one is called
ACCESS_WORDS = {"r": "read", "w": "write", "c": "call", "e": "event", "s": "stream", "m": "mission"}
_COMMANDS = {"r": "get", "w": "set", "c": "call", "e": "watch", "s": "watch", "m": "call"}
_LACKING = {"r": ("NotReadable", "read"), "w": ("NotWritable", "written"), "c": ("NotCallable", "called")}

#: printable excerpts of what a port said are cut to this many characters
EXCERPT_CHARS = 48


class Holder(NamedTuple):
    """A process that has a port open: its ``pid`` and command line."""

    pid: int
    command: str


class PortOpenError(HubwireError, OSError):
    """A port could not be opened; ``kind`` is ``PermissionDenied``, ``PortBusy``, ``NoSuchPort``
    or ``PortError`` (see :data:`ERROR_TYPES`)."""

    def __init__(self, kind: str, message: str, err: Optional[int] = None) -> None:
        HubwireError.__init__(self, message)
        self.kind = kind
        self.errno = err


def local_path(url: Optional[str]) -> Optional[str]:
    """The device file behind ``url`` (symlinks resolved), or None for ``socket://`` and the like."""
    if not url or "://" in url:
        return None
    return os.path.realpath(url)


# ------------------------------------------------------------------------------------ channels

def access_words(access: str) -> str:
    """Access letters in words: ``"rws"`` is ``"read, write, stream"``."""
    return ", ".join(ACCESS_WORDS[a] for a in access)


def access_error(name: str, access: str, need: str) -> Optional[Tuple[str, str]]:
    """``(error type, message)`` when channel ``name`` with ``access`` lacks the letter ``need``
    (``r``, ``w`` or ``c``); the message names the commands that do apply. None when it has it."""
    if need in access:
        return None
    kind, verb = _LACKING[need]
    uses = [f"`hubwire {c}`" for c in dict.fromkeys(_COMMANDS[a] for a in access)]
    alternatives = uses[0] if len(uses) == 1 else ", ".join(uses[:-1]) + " or " + uses[-1]
    return kind, f"channel {name!r} cannot be {verb}: its access is {access_words(access)}; use {alternatives}"


def blocked_loop_hint(gap_ms: Optional[int], declared_ms: Optional[int], silent: bool = False) -> str:
    """What to add to a lost link or an unanswered request when the device's heartbeats come far
    apart (``gap_ms``: measured by the device, or with ``silent`` a silence the hub heard;
    ``declared_ms``: the interval its hello announced): its sketch does not call ``hub.update()``
    often enough, most often because of ``delay()`` in ``loop()``. Empty otherwise."""
    if not gap_ms or not declared_ms or gap_ms < 3 * declared_ms:
        return ""
    seen = f"silent for {gap_ms} ms at a time" if silent else f"heartbeat every {gap_ms} ms"
    return f"; the board's loop() seems blocked ({seen}, declared {declared_ms} ms): avoid delay() in loop()"


def install_hint(extra: str) -> str:
    """How to install one of the package's extras (``mqtt``, ``dashboard``, ``service``): from the
    clone, since the package is not published on the package index."""
    return f"pip install './host[{extra}]' in your Hubwire clone (it is not on PyPI)"


#: what ``hubwire set`` and ``call`` add when the board restarted as the command opened its port
RESTART_NOTE = ("the board restarted when this command opened its port (as an Uno does), and will again at the "
                "next command, which then reads its start-up values; `hubwire serve` keeps it running (commands "
                "go through it)")


def failsafe_warning(name: str, failsafe: str, value: str) -> str:
    """What ``hubwire set`` warns when it writes ``value`` to a channel with a ``failsafe`` value."""
    return (f"{name} has a failsafe value ({failsafe}): the board sets it back from {value} to {failsafe} "
            f"about a second after this command's connection ends, when it sees the link lost; to hold "
            f"{value}, keep a program connected (hubwire.connect in Python)")


# ---------------------------------------------------------------------------- opening a port

def open_error_kind(exc: BaseException) -> str:
    """The error type of an exception raised while opening a port."""
    code = getattr(exc, "errno", None)
    if code in (errno.EACCES, errno.EPERM):
        return "PermissionDenied"
    # EBUSY: TIOCEXCL; EAGAIN: pyserial's exclusive=True lock; Windows says "Access is denied"
    if code in (errno.EBUSY, errno.EAGAIN) or "Access is denied" in str(exc):
        return "PortBusy"
    if code in (errno.ENOENT, errno.ENODEV, errno.ENXIO):
        return "NoSuchPort"
    return "PortError"


def _group_name(gid: int) -> Optional[str]:
    if grp is None:
        return None
    try:
        return grp.getgrgid(gid).gr_name
    except KeyError:
        return None


def permission_message(url: str) -> str:
    """Why ``url`` cannot be opened for lack of permission, and the command that fixes it."""
    group = "dialout"
    path = local_path(url)
    try:
        st = os.stat(path) if path else None
    except OSError:
        st = None
    # the port's own group when it is the one that may read and write it (uucp on Arch, ...)
    if st is not None and st.st_gid != 0 and st.st_mode & stat.S_IRGRP and st.st_mode & stat.S_IWGRP:
        group = _group_name(st.st_gid) or group
    try:
        user = pwd.getpwuid(os.getuid()).pw_name
        member = user in grp.getgrnam(group).gr_mem
    except (KeyError, AttributeError):  # AttributeError: no grp/pwd (Windows)
        member = False
    if member:
        return (f"no permission to open {url}: you were added to the '{group}' group after this login "
                f"started; log out and back in (a new login is needed for the group to apply)")
    return (f"no permission to open {url}: serial ports belong to the '{group}' group. Join it with "
            f"`sudo usermod -aG {group} $USER`, then log out and back in (a new login is needed "
            f"for the group to apply)")


def _holders_text(holders: Sequence[Holder]) -> str:
    return ", ".join(f"pid {h.pid} ({h.command})" for h in holders)


def busy_message(url: str, holders: Sequence[Holder]) -> str:
    """``url`` is in use by another program; ``holders`` (from :func:`port_holders`) names them."""
    if holders:
        pids = " ".join(str(h.pid) for h in holders)
        return (f"{url} is in use by another program: {_holders_text(holders)}. Close it (or `kill {pids}`) "
                f"and try again; only one program at a time can talk to a board")
    where = local_path(url) or url
    return (f"{url} is in use by another program (not one of yours, or not visible: `sudo lsof {where}` "
            f"names it). Close it and try again; only one program at a time can talk to a board")


def open_error_message(url: str, exc: BaseException, holders: Sequence[Holder] = ()) -> str:
    """The message for an exception raised while opening ``url`` (``holders``: for a busy port)."""
    kind = open_error_kind(exc)
    if kind == "PermissionDenied":
        return permission_message(url)
    if kind == "PortBusy":
        return busy_message(url, holders)
    if kind == "NoSuchPort":
        return f"there is no serial port {url}: is the board plugged in? `hubwire ports` lists the ports there are"
    return f"cannot open {url}: {exc}"


def open_error(url: str, exc: BaseException) -> PortOpenError:
    """A :class:`PortOpenError` for an exception raised while opening ``url``; looks up who holds a
    busy port. Raise it ``from exc``."""
    kind = open_error_kind(exc)
    holders = port_holders(url) if kind == "PortBusy" else []
    return PortOpenError(kind, open_error_message(url, exc, holders), getattr(exc, "errno", None))


# ------------------------------------------------------------------------------ who holds it

_PTY_SLAVE_MAJORS = range(136, 144)  # Unix98 pty slaves, /dev/pts/N


def _pty_index(rdev: int) -> Optional[int]:
    if os.major(rdev) in _PTY_SLAVE_MAJORS:
        return (os.major(rdev) - 136) * 256 + os.minor(rdev)
    return None


def _command(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            args = f.read().rstrip(b"\0").split(b"\0")
        text = " ".join(a.decode(errors="replace") for a in args if a)
    except OSError:
        text = ""
    if not text:
        try:
            with open(f"/proc/{pid}/comm") as f:
                text = f.read().strip()
        except OSError:
            text = "?"
    return text if len(text) <= 80 else text[:77] + "..."


def _holds(pid: int, target: os.stat_result, pty_index: Optional[int]) -> bool:
    """Whether ``pid`` has ``target`` open, not counting the board's side of a pty (an emulator
    holding both the master and the slave of the same pty)."""
    fd_dir = f"/proc/{pid}/fd"
    try:
        fds = os.listdir(fd_dir)
    except OSError:
        return False  # gone, or another user's process
    holds = master = False
    for fd in fds:
        try:
            st = os.stat(f"{fd_dir}/{fd}")
        except OSError:
            continue
        if stat.S_ISCHR(target.st_mode):
            if stat.S_ISCHR(st.st_mode) and st.st_rdev == target.st_rdev:
                holds = True
            elif pty_index is not None and stat.S_ISCHR(st.st_mode) and os.major(st.st_rdev) == 5:
                master = master or _is_master_of(pid, fd, pty_index)
        elif (st.st_dev, st.st_ino) == (target.st_dev, target.st_ino):
            holds = True
    return holds and not master


def _is_master_of(pid: int, fd: str, index: int) -> bool:
    try:
        with open(f"/proc/{pid}/fdinfo/{fd}") as f:
            return f"tty-index:\t{index}\n" in f.read()
    except OSError:
        return False


def port_holders(url: Optional[str], exclude: Sequence[int] = ()) -> List[Holder]:
    """Processes other than this one (and ``exclude``) that have the port behind ``url`` open.

    Scans ``/proc/*/fd``: without root it sees the user's own processes, which is where a second
    hub, a serial monitor or a forgotten ``screen`` usually is. Empty for URLs that are not local
    device files and where ``/proc`` does not exist.
    """
    path = local_path(url)
    if path is None:
        return []
    try:
        target = os.stat(path)
        pids = [int(p) for p in os.listdir("/proc") if p.isdigit()]
    except OSError:
        return []
    skip = {os.getpid(), *exclude}
    index = _pty_index(target.st_rdev) if stat.S_ISCHR(target.st_mode) else None
    return [Holder(pid, _command(pid)) for pid in sorted(pids) if pid not in skip and _holds(pid, target, index)]


# -------------------------------------------------------------------------- what was heard

def describe_noise(sample: bytes) -> Tuple[str, str]:
    """A short printable account of bytes that were not Hubwire frames: ``("text", '"..."')`` when
    they read as text (another sketch printing), else ``("bytes", "3f c1 ...")`` (another protocol,
    a wrong baud rate)."""
    body = sample.replace(b"\x00", b"")  # the frame delimiters the decoder kept with the sample
    printable = sum(1 for b in body if 32 <= b < 127 or b in (9, 10, 13))
    if body and printable >= 0.9 * len(body):
        lines = [ln.strip() for ln in body.decode("ascii", "replace").splitlines()]
        text = " | ".join(ln for ln in lines if ln)
        if len(text) > EXCERPT_CHARS:
            text = text[:EXCERPT_CHARS - 3] + "..."
        return "text", f'"{text}"'
    shown = sample[:16]
    return "bytes", " ".join(f"{b:02x}" for b in shown) + (" ..." if len(sample) > len(shown) else "")


def no_answer_message(url: str, timeout: float, counters: Mapping[str, int], sample: bytes, *,
                      frames: int = 0, hello_ms: Optional[int] = None) -> str:
    """Why no Hubwire device answered on ``url`` within ``timeout`` seconds.

    ``counters`` are the frame decoder's drop counters (``crc``, ``overflow``, ``dropped``),
    ``sample`` what it heard instead of frames (``FrameDecoder.noise()``), ``frames`` the valid
    frames it received, ``hello_ms`` how often the hub said hello.
    """
    head = f"no Hubwire device answered on {url} within {timeout:g} s"
    if sample and not frames:
        kind, said = describe_noise(sample)
        if kind == "text":
            return (f"{head}: text arrived, is another sketch on the board? It said: {said}. "
                    f"Upload a sketch that uses Hubwire")
        return (f"{head}: bytes that are not Hubwire frames arrived ({said}). Check the board runs a "
                f"Hubwire sketch at the hub's baud rate")
    if frames or any(counters.values()):
        heard = ", ".join(f"{k} {v}" for k, v in counters.items())
        return (f"{head}: frames arrived but no handshake completed ({frames} valid, dropped: {heard}); "
                f"is the line noisy, or the board restarting over and over?")
    hello = f"; a hello went out every {hello_ms} ms" if hello_ms else ""
    return (f"{head}: the port stayed silent (nothing arrived{hello}). Is the board plugged in, running a "
            f"sketch that uses Hubwire, and is this its port (`hubwire ports`)?")
