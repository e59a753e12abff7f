"""Ctrl-C (SIGINT) ends every ``hubwire`` command, and SIGTERM ``hubwire serve``, within
:data:`ENDS_WITHIN` seconds however busy the machine: the first signal starts the command's own
clean ending (a mission's run is cancelled, links close) and a countdown; what has not finished when the countdown runs out is
abandoned and the process exits with the command's status. A second Ctrl-C ends it at once."""
from __future__ import annotations

import os
import signal
import sys
import threading
from typing import Any, Callable, Optional

__all__ = ["ENDS_WITHIN", "CLEAN_WITHIN", "arm", "install"]

#: the promise: seconds from the signal to the end of the process
ENDS_WITHIN = 2.0
#: what the clean ending may take; the rest of ENDS_WITHIN is for the exit itself on a busy machine
CLEAN_WITHIN = 1.4

_lock = threading.Lock()
_armed: Optional[threading.Timer] = None


def _end(status: int) -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(status)


def arm(status: int, within: float = CLEAN_WITHIN) -> bool:
    """Start the countdown (once): the process exits with ``status`` ``within`` seconds from now
    whatever it is doing then. False when it was running already (a second signal)."""
    global _armed
    with _lock:
        if _armed is not None:
            return False
        _armed = threading.Timer(within, _end, (status,))
        _armed.daemon = True
        _armed.start()
        return True


def install(status: int, then: Optional[Callable[[], Any]] = None) -> None:
    """SIGINT starts the countdown with ``status``, then raises KeyboardInterrupt in the main thread
    (or calls ``then``); a second one exits at once. SIGTERM keeps its default: the end, at once."""

    def handler(signum: int, frame: Any) -> None:
        if not arm(status):
            _end(status)
        if then is not None:
            then()
        else:
            raise KeyboardInterrupt

    signal.signal(signal.SIGINT, handler)
