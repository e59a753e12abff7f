"""The soak's large values: the sketch's ``blob`` (a 40-byte struct ``token:u32, data:u8[32],
sum:u32``, more than the soak device's 32-byte frame) written and read back in fragments
(PROTOCOL.md 12) through the faulty link.

The hub writes blobs with strictly increasing tokens, data derived from the token and ``sum`` the
FNV-1a 32 of the token's 4 bytes (little-endian) then the data; the sketch counts blobs applied,
corrupt (the sum does not match: a torn or damaged value), twice (a token not above the last) and
gaps, in ``blob_counts``. Every read must be an intact blob the hub wrote. Per device boot:

- **lost**: blobs the device never applied beyond the writes the hub did not see acknowledged
  (sent - applied > unacknowledged), or a last acknowledged blob that is not the one it holds;
- **duplicated**: applied twice on the device (``twice``), or applied more often than sent;
- **corrupt**: applied with a wrong sum on the device, or read back with one by the hub.
"""
from __future__ import annotations

import struct
from typing import Any, Callable, Dict, List

from ...wire.messages import fnv1a32
from .soak_load import retry, wait_for

__all__ = ["blob_value", "intact", "BlobLoad", "check_blob_boot"]

#: a blob is written and read back every this many soak steps
EVERY = 5


def blob_value(token: int) -> Dict[str, Any]:
    data = [(token * 131 + i * 29 + (token >> 8)) & 0xFF for i in range(32)]
    return {"token": token, "data": data, "sum": fnv1a32(struct.pack("<I", token) + bytes(data))}


def intact(value: Any) -> bool:
    """A blob the hub could have written: its sum and its data are those of its token."""
    token = value[0]
    return bool(token > 0 and tuple(value[1]) == tuple(blob_value(token)["data"]) and value[2] == blob_value(token)["sum"])


class BlobLoad:
    """Writes and reads ``blob``; ``boots`` holds one count per device boot (:meth:`close_boot`)."""

    def __init__(self, dev: Any, log: Callable[[str], None]) -> None:
        import hubwire

        self.hw, self.dev, self.log = hubwire, dev, log
        self.token = self.k = 0
        self.boots: List[Dict[str, Any]] = []
        self._new_boot()

    def _new_boot(self) -> None:
        self.sent = self.acked = self.uncertain = self.reads = self.bad_reads = self.read_failures = 0
        self.naks = 0

    def step(self) -> None:
        self.k += 1
        if self.k % EVERY == 0 and self._write():
            self._read()

    def _write(self) -> bool:
        self.token += 1
        self.sent += 1
        try:
            self.dev.blob = blob_value(self.token)
            self.acked += 1
            return True
        except (self.hw.Timeout, self.hw.LinkLost):
            self.uncertain += 1
        except self.hw.NakError as e:
            self.uncertain += 1  # NOT_LINKED: refused, not applied (counted with the uncertain ones)
            if e.error != "NOT_LINKED":
                self.naks += 1
                self.log(f"soak: NAK on blob {self.token}: {e}")
        return False

    def _read(self) -> None:
        try:
            got = self.dev.blob
        except (self.hw.Timeout, self.hw.LinkLost, self.hw.NakError):
            self.read_failures += 1
            return
        self.reads += 1
        if not intact(got) or got[0] > self.token:
            self.bad_reads += 1
            self.log(f"soak: blob read back torn or never written: token {got[0]}")

    def close_boot(self) -> Dict[str, Any]:
        """On the clean link: one last acknowledged blob, then the device's counts."""
        while True:
            wait_for(lambda: self.dev.state == "ready", 30)
            if self._write():
                break
        held = retry(lambda: self.dev.blob, "read blob")
        applied, corrupt, twice, gaps = retry(lambda: self.dev.blob_counts, "read blob_counts")
        b = {"sent": self.sent, "acked": self.acked, "unacknowledged": self.uncertain, "applied": applied,
             "device_corrupt": corrupt, "twice": twice, "gaps": gaps, "last_sent": self.token,
             "held": held[0], "held_intact": intact(held), "reads": self.reads, "bad_reads": self.bad_reads,
             "read_failures": self.read_failures, "naks": self.naks}
        good = applied - corrupt - twice  # distinct blobs the sketch took (it counts the others apart)
        b["lost"] = max(0, self.sent - good - self.uncertain) + (0 if held[0] == self.token else 1)
        b["duplicated"] = twice + max(0, good - self.sent)
        b["corrupt"] = corrupt + self.bad_reads + (0 if intact(held) else 1)
        self.boots.append(b)
        self._new_boot()
        return b


def check_blob_boot(i: int, b: Dict[str, Any]) -> List[str]:
    """0 lost, 0 duplicated, 0 corrupt, and blobs really went through."""
    bad = []
    where = f"boot {i + 1}, blobs"
    for key in ("lost", "duplicated", "corrupt", "naks"):
        if b[key]:
            bad.append(f"{where}: {b[key]} {key} ({b})")
    if b["applied"] < 1 or b["reads"] < 1:
        bad.append(f"{where}: {b['applied']} applied, {b['reads']} read back: the large value was not exercised")
    if b["gaps"] > b["unacknowledged"]:
        bad.append(f"{where}: {b['gaps']} tokens skipped, more than the {b['unacknowledged']} unacknowledged writes")
    return bad
