"""The directory the service's socket lives in: made by the service (0700), and refused when another
user made it first, when anyone else may write to it, or when it is a symbolic link.

Whoever can connect to the socket commands every board, and whoever controls its directory can put
a socket of their own in its place: a user who creates ``/tmp/hubwire-1000`` before its owner would
own the service's door, or stand in for the service towards its clients. Under systemd the
directory is ``/run/hubwire`` (``RuntimeDirectory=``, mode 0750, the unit's group may connect).
"""
from __future__ import annotations

import errno
import logging
import os
import stat
from typing import Optional

from ..errors import HubwireError

__all__ = ["SocketDirError", "ensure_dir", "untrusted"]

log = logging.getLogger("hubwire.service")


class SocketDirError(HubwireError):
    """The socket's directory cannot be trusted (the message says what to do)."""

    kind = "SocketDirError"


def untrusted(d: str) -> Optional[str]:
    """Why the directory ``d`` cannot hold the service's socket, or None when it can: it must be a
    real directory (no symbolic link), owned by this process's user (or root, for a client), and
    writable by its owner only."""
    try:
        st = os.lstat(d)
    except FileNotFoundError:
        return f"{d} does not exist"
    if stat.S_ISLNK(st.st_mode):
        return f"{d} is a symbolic link"
    if not stat.S_ISDIR(st.st_mode):
        return f"{d} is not a directory"
    if st.st_uid not in (os.geteuid(), 0):
        return f"{d} is owned by uid {st.st_uid}, not by this user (uid {os.geteuid()})"
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        who = "every user" if st.st_mode & stat.S_IWOTH else "its group"
        return f"{d} is writable by {who} (mode {stat.S_IMODE(st.st_mode):o})"
    return None


def ensure_dir(sock: str) -> None:
    """Make the directory of the socket ``sock`` (mode 0700; its parent must exist), or check the
    one there: :class:`SocketDirError` when it cannot be trusted."""
    d = os.path.dirname(os.path.abspath(sock))
    try:
        os.mkdir(d, 0o700)
    except FileExistsError:
        pass
    except OSError as e:
        if e.errno != errno.EEXIST:
            raise SocketDirError(f"cannot make the socket's directory {d}: {e.strerror}") from None
    st = os.lstat(d)
    why = untrusted(d)
    if why is None and st.st_uid != os.geteuid():
        why = f"{d} is owned by uid {st.st_uid}, not by this user (uid {os.geteuid()})"
    if why is not None:
        raise SocketDirError(
            f"will not listen on {sock}: {why}. Another user may have made it to take the socket over: "
            f"remove it (rm -r {d}) and start again, or give --socket (or $HUBWIRE_SOCKET) a path in a "
            f"directory of your own (mode 0700, such as $XDG_RUNTIME_DIR/hubwire/hubwire.sock)")
