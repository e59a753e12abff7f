"""The soak's large-value accounting (hubwire.testing.faultlink.soak_large) sees what it must:
a blob applied twice, one lost, one torn, and a run that never exercised large values."""
from __future__ import annotations

from typing import Any, Dict

from hubwire.testing.faultlink.soak_large import blob_value, check_blob_boot, intact


def boot(**changes: Any) -> Dict[str, Any]:
    b = {"sent": 10, "acked": 8, "unacknowledged": 2, "applied": 9, "device_corrupt": 0, "twice": 0, "gaps": 1,
         "last_sent": 10, "held": 10, "held_intact": True, "reads": 8, "bad_reads": 0, "read_failures": 0,
         "naks": 0, "lost": 0, "duplicated": 0, "corrupt": 0}
    b.update(changes)
    return b


def test_a_clean_boot_passes_and_each_fault_is_named() -> None:
    assert check_blob_boot(0, boot()) == []
    assert any("duplicated" in x for x in check_blob_boot(0, boot(duplicated=1)))
    assert any("lost" in x for x in check_blob_boot(0, boot(lost=1)))
    assert any("corrupt" in x for x in check_blob_boot(0, boot(corrupt=2)))
    assert any("not exercised" in x for x in check_blob_boot(0, boot(applied=0)))
    assert any("skipped" in x for x in check_blob_boot(0, boot(gaps=3)))


def test_intact_blobs() -> None:
    v = blob_value(7)
    as_read = (v["token"], tuple(v["data"]), v["sum"])
    assert intact(as_read)
    assert not intact((7, tuple(v["data"]), v["sum"] ^ 1))           # wrong sum
    assert not intact((7, (v["data"][0] ^ 1,) + tuple(v["data"][1:]), v["sum"]))  # a torn byte
    assert not intact((8, tuple(v["data"]), v["sum"]))                # another token's data
    assert not intact((0, tuple(blob_value(0)["data"]), blob_value(0)["sum"]))  # never written


class FakeBoard:
    """Applies blobs as the soak sketch counts them, with a fault to inject."""

    state = "ready"

    def __init__(self, fault: str = "") -> None:
        object.__setattr__(self, "fault", fault)
        object.__setattr__(self, "held", None)
        object.__setattr__(self, "counts", [0, 0, 0, 0])
        object.__setattr__(self, "n", 0)

    def __setattr__(self, name: str, value: Any) -> None:
        assert name == "blob"
        n = self.n + 1
        object.__setattr__(self, "n", n)
        if self.fault == "lose" and n == 2:
            return  # acknowledged, never applied
        v = (value["token"], tuple(value["data"]), value["sum"])
        if self.fault == "tear" and n == 2:
            v = (v[0], (v[1][0] ^ 0x40,) + v[1][1:], v[2])
        self.counts[0] += 1 + (self.fault == "twice" and n == 2)
        self.counts[2] += self.fault == "twice" and n == 2
        self.counts[1] += not intact(v)
        if intact(v):
            object.__setattr__(self, "held", v)

    @property
    def blob(self) -> Any:
        return self.held

    @property
    def blob_counts(self) -> Any:
        return tuple(self.counts)


def run(fault: str) -> Dict[str, Any]:
    from hubwire.testing.faultlink.soak_large import EVERY, BlobLoad

    load = BlobLoad(FakeBoard(fault), lambda s: None)
    for _ in range(4 * EVERY):
        load.step()
    return load.close_boot()


def test_close_boot_counts_each_fault() -> None:
    clean = run("")
    assert (clean["sent"], clean["applied"], clean["reads"]) == (5, 5, 4)
    assert (clean["lost"], clean["duplicated"], clean["corrupt"]) == (0, 0, 0) and check_blob_boot(0, clean) == []
    assert run("lose")["lost"] == 1
    assert run("twice")["duplicated"] == 1
    assert run("tear")["corrupt"] >= 1
