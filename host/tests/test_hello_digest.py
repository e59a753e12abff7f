"""The hello's descriptor digest in the Python wire layer (PROTOCOL.md 3.1): ``Hello.digest`` holds
bytes 16..31 of a device hello, or None for a 16-byte hello (a device that sends no digest)."""
from __future__ import annotations

import hashlib
import json
import os

import pytest

from hubwire.wire import messages as m
from hubwire.wire.frame import Frame

VECTORS = os.path.join(os.path.dirname(__file__), "..", "..", "test", "vectors", "frames.json")
DESCRIPTOR = b'{"p":1,"n":"probe","ch":[{"id":1,"n":"duty","a":"rw","t":"i16","fs":0}]}'
DIGEST = hashlib.sha256(DESCRIPTOR).digest()[:16]


def device_hello(digest: object = None) -> m.Hello:
    return m.Hello(1, m.FLAG_DEVICE | m.FLAG_REPLY, 0xDEADBEEF, 32, 250, m.fnv1a32(DESCRIPTOR), len(DESCRIPTOR),
                   digest)


def test_sizes() -> None:
    assert (m.Hello.SIZE, m.Hello.DIGEST_SIZE, m.Hello.SIZE_WITH_DIGEST) == (16, 16, 32)


def test_a_hello_with_a_digest_packs_it_at_bytes_16_to_31() -> None:
    raw = device_hello(DIGEST).pack()
    assert len(raw) == 32
    assert raw[:16] == device_hello().pack()  # the 16 bytes old hubs read are unchanged
    assert raw[16:] == DIGEST
    back = m.Hello.unpack(raw)
    assert back == device_hello(DIGEST) and back.digest == DIGEST


def test_a_hello_without_a_digest_stays_16_bytes_and_decodes_to_none() -> None:
    raw = device_hello().pack()
    assert len(raw) == 16
    assert m.Hello.unpack(raw).digest is None
    hub = m.Hello(1, 0, 7, 255, 250)
    assert len(hub.pack()) == 16 and m.Hello.unpack(hub.pack()).digest is None


@pytest.mark.parametrize("extra", [1, 8, 15])
def test_fewer_than_16_trailing_bytes_are_no_digest(extra: int) -> None:
    raw = device_hello().pack() + DIGEST[:extra]
    assert m.Hello.unpack(raw).digest is None


def test_bytes_after_the_digest_are_ignored() -> None:
    back = m.Hello.unpack(device_hello(DIGEST).pack() + b"\x01\x02\x03")
    assert back.digest == DIGEST and back.descriptor_length == len(DESCRIPTOR)


@pytest.mark.parametrize("bad", [b"", b"\x00" * 15, b"\x00" * 17, b"\x00" * 32, "0" * 16])
def test_a_digest_of_another_length_or_type_is_refused(bad: object) -> None:
    with pytest.raises(ValueError):
        device_hello(bad)


def test_a_bytearray_digest_is_kept_as_bytes() -> None:
    h = device_hello(bytearray(DIGEST))
    assert type(h.digest) is bytes and h.digest == DIGEST


def test_describe_names_the_digest_only_when_sent() -> None:
    with_digest = m.describe(Frame(m.HELLO, 0, 0, device_hello(DIGEST).pack()))
    without = m.describe(Frame(m.HELLO, 0, 0, device_hello().pack()))
    assert with_digest.pop("descriptor_digest") == DIGEST.hex()
    assert with_digest == without and "descriptor_digest" not in without


def test_the_golden_vectors_hold_hellos_with_and_without_a_digest() -> None:
    with open(VECTORS, encoding="utf-8") as fh:
        hellos = [v for v in json.load(fh)["vectors"] if v["message"]["kind"] == "hello"]
    digested = [v for v in hellos if "descriptor_digest" in v["message"]]
    plain = [v for v in hellos if "descriptor_digest" not in v["message"]]
    assert len(digested) >= 2 and len(plain) >= 4
    for v in digested:
        h = m.Hello.unpack(bytes.fromhex(v["payload"]))
        assert h.digest is not None and h.digest.hex() == v["message"]["descriptor_digest"], v["name"]
        assert h.digest == DIGEST and (h.descriptor_hash, h.descriptor_length) == (m.fnv1a32(DESCRIPTOR),
                                                                                  len(DESCRIPTOR)), v["name"]
    for v in plain:
        assert m.Hello.unpack(bytes.fromhex(v["payload"])).digest is None, v["name"]
