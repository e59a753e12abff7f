"""Which serial ports are boards: the one filter on known USB vendor ids (used by ``connect()``
without a port, ``hubwire ports``, ``hubwire dashboard`` and the service's scan), and finding the
port of the one connected board."""
from __future__ import annotations

from typing import Any, Dict, List, Optional

from .errors import NoDeviceFound

__all__ = ["find_port", "KNOWN_USB_VIDS", "serial_ports", "board_kind", "board_ports", "PYTHON_ADVICE"]

#: the last sentence of find_port's error when no board is found (the command line says its own)
PYTHON_ADVICE = "Pass the port explicitly, e.g. connect('/dev/ttyACM0')."

#: USB vendor ids of boards and USB-serial bridges commonly used with microcontrollers
KNOWN_USB_VIDS: Dict[int, str] = {
    0x2341: "Arduino",
    0x2A03: "Arduino (.org)",
    0x1A86: "CH340",
    0x0403: "FTDI",
    0x10C4: "CP210x",
    0x16C0: "Teensy",
    0x2E8A: "RP2040",
    0x303A: "Espressif",
}


def serial_ports() -> List[Any]:
    """Every serial port pyserial sees (``ListPortInfo``), in the order of their device names."""
    from serial.tools import list_ports

    return sorted(list_ports.comports(), key=lambda p: str(p.device))


def board_kind(port: Any) -> Optional[str]:
    """What kind of board a port's USB vendor id says it is (``"Arduino"``, ``"CH340"``...), or None
    for a port that is not a known board."""
    vid = getattr(port, "vid", None)
    return KNOWN_USB_VIDS.get(vid) if vid is not None else None


def board_ports(ports: Optional[List[Any]] = None) -> List[Any]:
    """The ports (of ``ports``, else every serial port) whose USB vendor id is a known board's."""
    return [p for p in (serial_ports() if ports is None else ports) if board_kind(p) is not None]


def _port_line(p: Any) -> str:
    ids = f"{p.vid:04x}:{p.pid:04x}" if p.vid is not None else "no USB id"
    desc = p.description if p.description and p.description != "n/a" else ""
    return f"{p.device} ({ids}{', ' + desc if desc else ''})"


def find_port() -> str:
    """Serial port of the one connected board with a known USB vendor id.

    Raises NoDeviceFound naming the ports seen when none or several match.
    """
    ports = serial_ports()
    matches = board_ports(ports)
    if len(matches) == 1:
        return str(matches[0].device)
    seen = "; ".join(_port_line(p) for p in ports) or "none"
    if not matches:
        raise NoDeviceFound(
            "no microcontroller board found: no serial port has a known USB id "
            f"({', '.join(f'{v:04x} {n}' for v, n in KNOWN_USB_VIDS.items())}). Ports seen: {seen}. "
            + PYTHON_ADVICE)
    raise NoDeviceFound(
        f"{len(matches)} boards found, pass the one to use explicitly: "
        + "; ".join(f"{_port_line(p)} [{board_kind(p)}]" for p in matches))
