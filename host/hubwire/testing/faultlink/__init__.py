"""faultlink: a faulty serial line on demand (bit errors, drops, duplicates, truncation, garbage,
delay, stalls), reproducible from a seed and counted.

- :class:`FaultyTransport`: the faults inside the hub process, wrapped around any transport;
- :class:`FaultLink`: the same faults in a pty proxy between a hub and a device's pty (for pulling
  the plug: the hub's pty vanishes with :meth:`FaultLink.stop`), also a command:
  ``python -m hubwire.testing.faultlink --help``.
"""
from .faults import DirectionStats, Faults
from .proxy import FaultLink, stop_process
from .transport import FaultyTransport

__all__ = ["Faults", "DirectionStats", "FaultLink", "FaultyTransport", "stop_process"]
