"""The device proxy: channels never shadow or replace its methods and properties; every channel is
reachable by key; attribute access for the names that do not clash; a one-line repr."""
from __future__ import annotations

from typing import Iterator

import pytest

import hubwire
from hubwire.session import Session

from fakedevice import FakeDevice

CLASHING = (b'{"p":1,"n":"clash","ch":[{"id":1,"n":"close","a":"rw","t":"u16"},{"id":2,"n":"read","a":"rw","t":"u16"},'
            b'{"id":3,"n":"session","a":"rw","t":"u16"},{"id":4,"n":"__class__","a":"rw","t":"u16"},'
            b'{"id":5,"n":"name","a":"rw","t":"u16"},{"id":6,"n":"free","a":"rw","t":"u16"}]}')


@pytest.fixture
def clash(cache_dir: str) -> Iterator[tuple]:
    with FakeDevice(CLASHING) as fake, hubwire.connect(fake.path, cache_dir=cache_dir) as dev:
        yield fake, dev


def test_assigning_a_clashing_name_never_writes_the_channel(clash: tuple) -> None:
    fake, dev = clash
    for name in ("close", "read", "session", "name"):
        with pytest.raises(AttributeError) as e:
            setattr(dev, name, 7)
        assert f"dev[{name!r}]" in str(e.value)
    with pytest.raises((AttributeError, TypeError)):
        dev.__class__ = 7  # type: ignore[assignment]
    assert fake.x == 0  # nothing was written
    assert dev.__class__ is hubwire.Device and isinstance(dev.session, Session)
    assert callable(dev.close) and callable(dev.read) and dev.name == "clash"


def test_every_channel_is_reachable_by_key(clash: tuple) -> None:
    fake, dev = clash
    for value, name in enumerate(("close", "read", "session", "__class__", "name", "free"), start=1):
        dev[name] = value
        assert fake.x == value and dev[name] == value and dev.read(name) == value
        assert name in dev


def test_free_names_keep_attribute_access(clash: tuple) -> None:
    fake, dev = clash
    dev.free = 42
    assert fake.x == 42 and dev.free == 42
    assert "free" in dir(dev) and "close" in dir(dev)
    with pytest.raises(AttributeError):
        dev.nope = 1
    with pytest.raises(AttributeError):
        del dev.free


def test_repr_is_one_line_and_the_table_is_separate(clash: tuple) -> None:
    _, dev = clash
    text = repr(dev)
    assert "\n" not in text and "'clash'" in text and "6 channels" in text and "ready" in text
    table = dev.table()
    assert table.count("\n") == 7 and "__class__" in table and "session" in table
