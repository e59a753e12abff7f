"""Device-supplied text stays bounded in errors and logs, descriptor chunk errors name the right
offsets, a full event queue says so, and docs/RELIABILITY.md quotes the messages the code prints."""
from __future__ import annotations

import json
import logging
import os
import re
from types import SimpleNamespace
from typing import Any, List

import pytest

import hubwire
from hubwire.errors import DescriptorError
from hubwire.descriptor import parse_descriptor
from hubwire.session.discovery import _Download
from hubwire.session.events import QueueSink
from hubwire.session.records import ReceivedEvent, Stats
from hubwire.text import clip, clip_json, clip_list
from hubwire.wire import messages as m

from .conftest import REPO, HostileDevice

HUGE = 10_000
BOUND = 600  # a message with device strings in it stays readable: a few lines, not 10,000 characters


# ------------------------------------------------------------------------------ clip itself

def test_clip_keeps_the_start_says_how_much_was_cut_and_escapes_control_characters() -> None:
    assert clip("abc") == "'abc'"
    long = clip("x" * HUGE)
    assert long.startswith("'xxxx") and long.endswith(f"…' (+{HUGE + 2 - 80} chars)") and len(long) < 110
    assert clip("a\x1b[2Jb\n") == r"'a\x1b[2Jb\n'"
    assert clip_json("y" * HUGE).endswith("chars)") and len(clip_json("y" * HUGE)) < 110
    assert clip_list(["a", "b"]) == "a, b"
    listed = clip_list([f"c{i}" for i in range(1000)])
    assert listed.startswith("c0, c1, ") and listed.endswith("more)") and len(listed) < 400


# ------------------------------------------------------------------- descriptor chunk errors

def download(total: int = 100) -> _Download:
    core = SimpleNamespace(progress_at=0.0)
    return _Download(core, total, 28)


def chunk(offset: int, total: int, data: bytes) -> Any:
    return SimpleNamespace(type=m.CHUNK, payload=m.Chunk(offset, total, data).pack())


def test_a_chunk_for_another_offset_names_the_asked_and_the_answered_offset() -> None:
    with pytest.raises(DescriptorError) as e:
        download()._take(60, chunk(0, 100, b"x" * 10))
    assert "asked for offset 60 answers offset 0" in str(e.value)


def test_a_chunk_running_past_the_end_says_so() -> None:
    with pytest.raises(DescriptorError) as e:
        download()._take(95, chunk(95, 100, b"x" * 10))
    assert "at offset 95 with 10 bytes runs past the end of the 100-byte descriptor" in str(e.value)


# ------------------------------------------------------------------------ hostile descriptors

def doc(**top: Any) -> str:
    d = {"p": 1, "n": "dev", "ch": [{"id": 1, "n": "x", "a": "rw", "t": "u8"}]}
    d.update(top)
    return json.dumps(d)


def chan(**kw: Any) -> str:
    c = {"id": 1, "n": "x", "a": "rw", "t": "u8"}
    c.update(kw)
    return doc(ch=[c])


EVIL = "\x1b[2J" + "N" * HUGE
HOSTILE = {
    "channel name": chan(n=EVIL),
    "long channel name": chan(n="n" * HUGE),
    "type": chan(t=EVIL),
    "access": chan(a="rw" + "z" * HUGE),
    "unit not a string": chan(u=["u" * HUGE]),
    "device name not a string": doc(n=[EVIL]),
    "firmware not a string": doc(fw={"v": EVIL}),
    "unknown keys": doc(**{f"k{i}" + "q" * 50: 1 for i in range(300)}),
    "field name": chan(t="struct", f=[{"n": EVIL, "t": "u8"}]),
    "duplicate name": doc(ch=[{"id": 1, "n": "x", "a": "r", "t": "u8"}, {"id": 2, "n": "x", "a": "r", "t": "u8"}]),
}


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_hostile_descriptor_errors_stay_bounded(case: str) -> None:
    with pytest.raises(DescriptorError) as e:
        parse_descriptor(HOSTILE[case])
    msg = str(e.value)
    assert len(msg) < BOUND, f"{case}: {len(msg)} characters"
    assert "\x1b" not in msg


def test_a_valid_descriptor_with_huge_strings_keeps_errors_and_logs_bounded(caplog: Any) -> None:
    desc = json.dumps({"p": 1, "n": EVIL, "fw": "f" * 500, "ch": [
        {"id": i, "n": f"channel_{i:03d}_" + "w" * 16, "a": "e" if i == 1 else "rw", "t": "u8",
         "u": "u" * 200 if i < 4 else "", "d": "d" * 500 if i < 4 else ""} for i in range(1, 31)]}).encode()
    assert len(desc) <= hubwire.descriptor.MAX_DESCRIPTOR_SIZE
    with HostileDevice(desc, max_payload=255) as d, hubwire.connect(d.path, cache_dir=False) as dev:
        errors: List[str] = []
        for op in (lambda: dev.nosuch, lambda: dev.channel("nosuch"), lambda: setattr(dev, "nosuch", 1)):
            with pytest.raises((AttributeError, KeyError)) as e:
                op()
            errors.append(str(e.value))
        errors.append(repr(dev))
        for text in errors:
            assert len(text) < BOUND and "\x1b" not in text, text[:200]
        assert "chars)" in errors[0] and "more)" in errors[0]  # cut, and saying so
        with caplog.at_level(logging.WARNING, logger="hubwire"):
            d.frame(m.EVENT, 1, 1, b"")  # malformed: a u8 event with no byte
            assert settle_log(caplog, "malformed event")
        assert all(len(r.getMessage()) < BOUND for r in caplog.records)


def settle_log(caplog: Any, words: str, timeout: float = 5.0) -> bool:
    from .conftest import settle
    return settle(lambda: any(words in r.getMessage() for r in caplog.records), timeout)


# ------------------------------------------------------------------------ full event queues

def ev(i: int) -> ReceivedEvent:
    return ReceivedEvent("bumper", True, i & 0xFF, 0.0, 8)


def drop_warnings(caplog: Any) -> int:
    return sum("event queue is full" in r.getMessage() for r in caplog.records if r.levelno == logging.WARNING)


def test_a_full_event_queue_warns_once_and_again_after_it_recovered(caplog: Any) -> None:
    stats = Stats()
    sink = QueueSink(stats, limit=8)
    with caplog.at_level(logging.WARNING, logger="hubwire"):
        for i in range(8):
            sink.put(ev(i))
        assert drop_warnings(caplog) == 0 and stats.events_dropped == 0
        for i in range(20):
            sink.put(ev(i))
        assert stats.events_dropped == 20 and drop_warnings(caplog) == 1  # told once, not 20 times
        sink.q.get_nowait()
        sink.put(ev(0))  # one read is not catching up: still the same episode
        sink.put(ev(0))
        assert drop_warnings(caplog) == 1
        while sink.q.qsize() > 4:  # the reader caught up to half
            sink.q.get_nowait()
        for i in range(6):
            sink.put(ev(i))
        assert stats.events_dropped == 23 and drop_warnings(caplog) == 2


def test_a_full_async_event_queue_warns_too(caplog: Any) -> None:
    from hubwire.aio import _AsyncSink

    async def main() -> None:
        core = SimpleNamespace(stats=Stats())
        sink = _AsyncSink(core, None)  # type: ignore[arg-type]
        sink.limit = 4
        for i in range(10):
            sink.put(ev(i))
        assert core.stats.events_dropped == 6 and len(sink.q) == 4

    import asyncio
    with caplog.at_level(logging.WARNING, logger="hubwire"):
        asyncio.run(main())
    assert drop_warnings(caplog) == 1


# --------------------------------------------------------------- RELIABILITY.md quotes the code

def package_source() -> str:
    root = os.path.join(REPO, "host", "hubwire")
    text = []
    for d, _, files in os.walk(root):
        text += [open(os.path.join(d, f), encoding="utf-8").read() for f in files if f.endswith(".py")]
    # adjacent string literals split over lines read as one
    return re.sub(r'"\s*\n\s*f?"', "", "\n".join(text))


PLACEHOLDER = re.compile(r"\.\.\.|\b(?:N|T|PATH)\b|\d[\d ]*")


def test_reliability_caps_table_quotes_messages_the_code_prints() -> None:
    doc_text = open(os.path.join(REPO, "docs", "RELIABILITY.md"), encoding="utf-8").read()
    table = doc_text.split("## Hard caps (hub)", 1)[1].split("\n\n", 2)[1]
    quoted = [q for row in table.splitlines() for q in re.findall(r"`([^`]+)`", row.split("|")[4])
              if re.match(r"^(?:[A-Z]\w+|hubwire): ", q)]
    assert len(quoted) >= 5, quoted
    src = package_source()
    for q in quoted:
        text = q.split(": ", 1)[1] if re.match(r"^[A-Z]\w+: ", q) else q  # the exception's class name
        for piece in PLACEHOLDER.split(text):
            piece = piece.strip(" ;.")
            if len(piece) > 3:
                assert piece in src, f"RELIABILITY.md quotes {q!r}, the code does not print {piece!r}"
