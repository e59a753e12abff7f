"""The descriptor cache cannot be poisoned (PROTOCOL.md 7.1): a board that serves a tampered
descriptor with the genuine one's length and FNV-1a hash (found in about a second, see
fnv_collision.py) never makes the hub serve it to the genuine board; the cache is keyed and checked
by the SHA-256 digest the device announces."""
from __future__ import annotations

import os

import pytest

import hubwire
from hubwire.descriptor.cache import descriptor_digest
from hubwire.wire.messages import fnv1a32

from fakedevice import FakeDevice
from fnv_collision import collide_in_text

# Two motors: "left" is channel 1, "right" channel 2. The rogue swaps the ids and fixes the hash up
# by changing six characters of the description.
GENUINE = (b'{"p":1,"n":"rover","ch":[{"id":1,"n":"left","a":"rw","t":"u16","d":"left motor, mm/s"},'
           b'{"id":2,"n":"right","a":"rw","t":"u16","d":"right motor, mm/s"}]}')


def _rogue() -> bytes:
    swapped = GENUINE.replace(b'"id":1,"n":"left"', b'"id":9,"n":"left"').replace(
        b'"id":2,"n":"right"', b'"id":1,"n":"right"').replace(b'"id":9,"n":"left"', b'"id":2,"n":"left"')
    forged, _ = collide_in_text(swapped, b"left motor", target=fnv1a32(GENUINE))
    return forged


ROGUE = _rogue()


def test_the_rogue_descriptor_really_collides() -> None:
    assert ROGUE != GENUINE and b'"id":2,"n":"left"' in ROGUE
    assert len(ROGUE) == len(GENUINE) and fnv1a32(ROGUE) == fnv1a32(GENUINE)
    assert descriptor_digest(ROGUE) != descriptor_digest(GENUINE)


def test_a_rogue_board_first_does_not_make_the_genuine_board_drive_the_wrong_motor(cache_dir: str) -> None:
    with FakeDevice(ROGUE) as rogue, hubwire.connect(rogue.path, cache_dir=cache_dir) as dev:
        assert dev.channel("left").id == 2  # the rogue's own descriptor, for its own session
        assert dev.session.stats.downloads == 1
    assert os.listdir(cache_dir) == [f"sha256-{descriptor_digest(ROGUE).hex()}.json"]
    with FakeDevice(GENUINE) as genuine, hubwire.connect(genuine.path, cache_dir=cache_dir) as dev:
        stats = dev.session.stats
        assert (stats.downloads, stats.cache_hits) == (1, 0), "the rogue's entry must not be used"
        dev.write("left", 500)
        assert genuine.writes == [(1, 500)]
    assert sorted(os.listdir(cache_dir)) == sorted(f"sha256-{descriptor_digest(d).hex()}.json"
                                                   for d in (GENUINE, ROGUE))
    # the genuine board again: now from its own entry
    with FakeDevice(GENUINE) as genuine, hubwire.connect(genuine.path, cache_dir=cache_dir) as dev:
        assert (dev.session.stats.downloads, dev.session.stats.cache_hits) == (0, 1)
        assert dev.channel("left").id == 1


def test_a_board_lying_about_its_digest_is_refused_and_nothing_is_cached(cache_dir: str) -> None:
    with FakeDevice(ROGUE, digest=descriptor_digest(GENUINE)) as rogue:
        with pytest.raises(hubwire.DescriptorError) as e:
            hubwire.connect(rogue.path, cache_dir=cache_dir, timeout=3.0)
    assert "digest mismatch" in str(e.value)
    assert not os.path.exists(cache_dir) or os.listdir(cache_dir) == []


def test_a_tampered_cache_file_is_not_used(cache_dir: str) -> None:
    os.makedirs(cache_dir, exist_ok=True)
    with open(os.path.join(cache_dir, f"sha256-{descriptor_digest(GENUINE).hex()}.json"), "wb") as fh:
        fh.write(ROGUE)  # planted on disk under the genuine board's name
    with FakeDevice(GENUINE) as genuine, hubwire.connect(genuine.path, cache_dir=cache_dir) as dev:
        assert (dev.session.stats.downloads, dev.session.stats.cache_hits) == (1, 0)
        assert dev.channel("left").id == 1


def test_a_board_without_a_digest_is_always_downloaded_and_never_cached(cache_dir: str) -> None:
    for _ in range(2):
        with FakeDevice(GENUINE, digest=False) as old, hubwire.connect(old.path, cache_dir=cache_dir) as dev:
            assert dev.session.device_hello.digest is None
            assert (dev.session.stats.downloads, dev.session.stats.cache_hits) == (1, 0)
    assert not os.path.exists(cache_dir) or os.listdir(cache_dir) == []
