"""Where the service looks for boards: USB serial ports with a known vendor id (pyserial's
``list_ports``), ports and URLs named on the command line, and watched glob patterns (a directory
where ptys or ``/dev/serial/by-id`` links come and go). With pyudev the service hears USB hotplug
at once; without it, it notices on its next poll."""
from __future__ import annotations

import asyncio
import glob
import logging
import os
from typing import Any, Callable, Dict, List, NamedTuple, Optional

from ..ports import board_ports, serial_ports

__all__ = ["PortInfo", "PortScanner", "is_path"]

log = logging.getLogger("hubwire.service")


class PortInfo(NamedTuple):
    """A port seen by a scan: the path to open and the USB serial number behind it (if any)."""

    path: str
    serial: Optional[str]


def is_path(url: str) -> bool:
    """A file system path (a port or pty that comes and goes), not a ``socket://``-like URL."""
    return "://" not in url


class PortScanner:
    """One scan gives every port present now, keyed by its real path (symlinks resolved)."""

    def __init__(self, ports: List[str], globs: List[str], *, usb: bool = True,
                 lister: Optional[Callable[[], List[Any]]] = None) -> None:
        self.ports = list(ports)
        self.globs = list(globs)
        self.usb = usb
        self._lister = lister

    def _usb_ports(self) -> List[Any]:
        if self._lister is not None:
            return self._lister()
        return serial_ports()

    def scan(self) -> Dict[str, PortInfo]:
        seen: Dict[str, PortInfo] = {}
        if self.usb:
            for p in board_ports(self._usb_ports()):
                if os.path.exists(p.device):
                    seen[os.path.realpath(p.device)] = PortInfo(p.device, p.serial_number or None)
        for url in self.ports:
            if not is_path(url):
                seen.setdefault(url, PortInfo(url, None))
            elif os.path.exists(url):
                seen.setdefault(os.path.realpath(url), PortInfo(url, None))
        for pattern in self.globs:
            for path in sorted(glob.glob(pattern)):
                if os.path.exists(path):  # not a link left dangling by a device that went away
                    seen.setdefault(os.path.realpath(path), PortInfo(path, None))
        return seen

    def udev_monitor(self, loop: asyncio.AbstractEventLoop, wake: Callable[[], None]) -> Optional[Callable[[], None]]:
        """Call ``wake()`` on every tty hotplug event (pyudev); returns the function stopping it, or
        None without pyudev or udev (the service then polls)."""
        try:
            import pyudev  # type: ignore[import-not-found,import-untyped,unused-ignore]

            monitor = pyudev.Monitor.from_netlink(pyudev.Context())
            monitor.filter_by("tty")
            monitor.start()
        except Exception as e:  # noqa: BLE001 - ImportError, no udev (a container), no netlink
            log.info("hubwire serve: no udev hotplug events (%s); polling for ports", e)
            return None

        def readable() -> None:
            while monitor.poll(0) is not None:
                pass
            wake()

        fd = monitor.fileno()
        loop.add_reader(fd, readable)

        def stop() -> None:
            loop.remove_reader(fd)
        return stop
