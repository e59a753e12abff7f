"""What `hubwire serve` keeps across its own restart (docs/SERVICE.md, "What survives a restart"):
kill -9 of the service during a flood of events both ways, then a new service on the same state.

Device events are counted by a client of the socket protocol (resuming with the last event id it
saw); hub events by the soak sketch itself (``tick``: applied, twice, gaps).
"""
from __future__ import annotations

import json
import os
import signal
import socket
import time
from typing import Any, Dict, List, Optional

import pytest

import hubwire
from conftest import Emulator
from hubwire.testing import repo_root
from hubwire.transport import SerialTransport

from .conftest import Serve, wait_for

SOAK = os.path.join(repo_root() or os.getcwd(), "build", "emulator", "hubwire-soak-emulator")


class Raw:
    """A client of the socket protocol, one JSON line each way (requests, answers, pushes)."""

    def __init__(self, path: str) -> None:
        self.sock = socket.socket(socket.AF_UNIX)
        self.sock.connect(path)
        self.sock.settimeout(30)
        self.buf = b""
        self.next = 0
        self.answers: Dict[int, Dict[str, Any]] = {}
        self.events: List[Dict[str, Any]] = []
        self.closed = False
        assert self._line()["service"] == "hubwire"

    def _line(self) -> Dict[str, Any]:
        while b"\n" not in self.buf:
            chunk = self.sock.recv(65536)
            if not chunk:
                self.closed = True
                raise ConnectionError("the service went away")
            self.buf += chunk
        line, self.buf = self.buf.split(b"\n", 1)
        return json.loads(line)  # type: ignore[no-any-return]

    def pump(self) -> Dict[str, Any]:
        msg = self._line()
        if "event" in msg:
            self.events.append(msg["event"])
        elif "id" in msg:
            self.answers[msg["id"]] = msg
        return msg

    def send(self, op: str, **kw: Any) -> int:
        self.next += 1
        self.sock.sendall((json.dumps({"id": self.next, "op": op, **kw}) + "\n").encode())
        return self.next

    def answer(self, rid: int) -> Dict[str, Any]:
        while rid not in self.answers:
            self.pump()
        return self.answers.pop(rid)

    def request(self, op: str, **kw: Any) -> Dict[str, Any]:
        return self.answer(self.send(op, **kw))

    def drain(self, until: float) -> None:
        """Read what comes until the service goes away or ``until`` (monotonic) passes."""
        while time.monotonic() < until:
            self.sock.settimeout(max(0.01, until - time.monotonic()))
            try:
                self.pump()
            except (socket.timeout, ConnectionError):
                if self.closed:
                    return
        self.sock.settimeout(30)

    def close(self) -> None:
        self.sock.close()


def kill9(serve: Serve) -> None:
    assert serve.proc is not None
    serve.proc.send_signal(signal.SIGKILL)
    serve.proc.wait(10)
    serve.proc = None


def ready_client(serve: Serve, key: str) -> Raw:
    """A new client once the service knows the board and has it ready."""
    def ok() -> Optional[Raw]:
        c = Raw(serve.socket)
        b = c.request("list")
        if any(x["key"] == key and x["state"] == "ready" for x in b["boards"]):
            return c
        c.close()
        return None
    return wait_for(ok, 30, f"board {key} ready")  # type: ignore[no-any-return]


@pytest.fixture
def soak(boards_dir: str) -> Any:
    if not os.access(SOAK, os.X_OK):
        pytest.fail(f"soak emulator not found at {SOAK}: build it with `make emulator`", pytrace=False)
    emu = Emulator(SOAK, os.path.join(boards_dir, "soak"))
    emu.start()
    yield emu
    emu.stop()


def test_device_events_survive_kill9_of_the_service(serve: Serve, soak: Emulator) -> None:
    """Events the board sent while the client was subscribed: each one reaches it once, across
    three kill -9 of the service in the middle of a flood (the client resumes with ``after``)."""
    c = ready_client(serve, "soak")
    sub = 1
    first = c.request("events", board="soak", names=["bumper"], sub=sub)
    assert first["ok"], first
    last = first.get("last", 0)
    expected = 0
    for _round in range(3):
        for _ in range(40):  # the board queues up to 4 per call; they flow while the next call runs
            r = c.request("call", board="soak", channel="selftest", arg=4)
            assert r["ok"], r
            expected += r["value"]
        kill9(serve)  # the last call's events are on their way: the device, the service, the socket
        c.drain(time.monotonic() + 2)
        c.close()
        if c.events:
            last = c.events[-1].get("id", last)
        serve.start()
        got = c.events
        c = ready_client(serve, "soak")
        c.events = got
        sub += 1
        r = c.request("events", board="soak", names=["bumper"], sub=sub, after=last)
        assert r["ok"], r
        assert r.get("missed", 0) == 0 and not r.get("reset"), (last, r, serve.log_text()[-3000:])
    deadline = time.monotonic() + 30
    while len(c.events) < expected and time.monotonic() < deadline:
        c.drain(min(deadline, time.monotonic() + 1))
    c.drain(time.monotonic() + 1)  # a duplicate would come now
    ids = [e.get("id") for e in c.events]
    print(f"device events: {expected} sent by the board, {len(c.events)} received, "
          f"{len(ids) - len(set(ids))} ids twice")
    assert len(c.events) == expected, (f"{expected} events sent, {len(c.events)} received: ids {ids}",
                                       serve.log_text()[-3000:])
    assert ids == list(range(ids[0], ids[0] + len(ids))), "event ids: each once, in order"
    c.close()


def test_hub_events_survive_kill9_of_the_service(serve: Serve, soak: Emulator) -> None:
    """Hub events the service accepted (``notify`` answered ok): all reach the device exactly once
    after a kill -9 of the service while they flow (the new service resumes the hub session: the
    same hub nonce, the event in flight re-sent with its seq, so the device re-acks it)."""
    n = 1500
    c = ready_client(serve, "soak")
    rids = [c.send("notify", board="soak", channel="tick", value=t) for t in range(1, n + 1)]
    for rid in rids:
        a = c.answer(rid)
        assert a["ok"], a
    wait_for(lambda: c.request("read", board="soak", channel="tick_last")["value"] >= n // 5, 30, "ticks flowing")
    kill9(serve)
    c.close()
    serve.start()
    c = ready_client(serve, "soak")
    counts = _tick_counts(serve, c, n)
    print(f"hub events: {n} accepted, device counts {counts}")
    assert counts["tick_first"] == 1 and counts["tick_gaps"] == 0, counts
    assert counts["tick_twice"] == 0, f"{counts['tick_twice']} hub event applied twice: {counts}"
    assert counts["ticks"] == n, counts
    c.close()


def _tick_counts(serve: Serve, c: Any, n: int) -> Dict[str, int]:
    """Once the board applied hub event ``n``: its own counts of the ticks it applied."""
    def read(ch: str) -> int:
        r = c.request("read", board="soak", channel=ch)
        assert "value" in r, (r, serve.log_text()[-3000:])
        return int(r["value"])
    wait_for(lambda: read("tick_last") == n, 60, f"tick {n} applied")
    return {ch: read(ch) for ch in ("ticks", "tick_first", "tick_last", "tick_twice", "tick_gaps")}


def test_hub_events_after_kill9_and_a_board_reboot(serve: Serve, soak: Emulator) -> None:
    """The board reboots while the service is down: the restarted service says hello with the kept
    hub nonce, but the board's new session remembers nothing and takes every kept event as new (the
    one in flight included): from where it was, in order, none lost."""
    n = 1500
    c = ready_client(serve, "soak")
    rids = [c.send("notify", board="soak", channel="tick", value=t) for t in range(1, n + 1)]
    for rid in rids:
        assert c.answer(rid)["ok"]
    wait_for(lambda: c.request("read", board="soak", channel="tick_last")["value"] >= n // 5, 30, "ticks flowing")
    kill9(serve)
    c.close()
    with hubwire.connect(transport=SerialTransport(soak.link), timeout=10, hub_later=True) as d:  # (no service now)
        before = int(d.read("tick_last"))  # the last one applied: the next one was in flight, or not sent
    soak.stop()
    soak.start()  # its counters start again from 0
    serve.start()
    c = ready_client(serve, "soak")
    counts = _tick_counts(serve, c, n)
    print(f"hub events across a board reboot: {n} accepted, {before} applied before it, device counts "
          f"after it {counts}")
    assert counts["tick_first"] in (before, before + 1), (before, counts)  # the one in flight, or the next
    assert counts["tick_gaps"] == 0 and counts["tick_twice"] == 0, counts
    assert counts["ticks"] == n - counts["tick_first"] + 1, counts
    c.close()


def test_notify_when_full_is_refused_and_the_kept_ones_all_arrive(serve: Serve, soak: Emulator) -> None:
    """A board that answers nothing (stopped): the service keeps HUB_EVENT_LIMIT hub events for it and
    refuses the next one; killed and restarted meanwhile, it delivers every one it accepted."""
    from hubwire.daemon.store import HUB_EVENT_LIMIT

    c = ready_client(serve, "soak")
    c.request("notify", board="soak", channel="tick", value=1)  # the board is bound: hub events flow
    wait_for(lambda: c.request("read", board="soak", channel="tick_last")["value"] == 1, 30, "tick 1")
    soak.pause()
    rids = [c.send("notify", board="soak", channel="tick", value=t) for t in range(2, HUB_EVENT_LIMIT + 3)]
    answers = [c.answer(rid) for rid in rids]
    ok = [a for a in answers if a["ok"]]
    refused = [a for a in answers if not a["ok"]]
    assert len(ok) == HUB_EVENT_LIMIT and answers[:HUB_EVENT_LIMIT] == ok, "the first ones are kept"
    assert len(refused) == 1 and "wait for" in refused[0]["message"], refused
    kill9(serve)
    c.close()
    serve.start()
    soak.resume()
    c = ready_client(serve, "soak")
    last = HUB_EVENT_LIMIT + 1

    def read(ch: str) -> int:
        r = c.request("read", board="soak", channel=ch)
        assert "value" in r, (r, serve.log_text()[-3000:])
        return int(r["value"])
    wait_for(lambda: read("tick_last") == last, 120, f"tick {last} applied")
    counts = {ch: read(ch) for ch in ("ticks", "tick_first", "tick_last", "tick_twice", "tick_gaps")}
    print(f"hub events when full: {len(ok) + 1} accepted, 1 refused, device counts {counts}")
    assert counts["tick_gaps"] == 0 and counts["tick_twice"] == 0, counts
    assert counts["ticks"] == last, counts
    c.close()


def test_notify_while_unplugged_reaches_the_board_when_it_comes_back(serve: Serve, soak: Emulator) -> None:
    c = ready_client(serve, "soak")
    soak.stop()
    wait_for(lambda: any(b["key"] == "soak" and b["state"] == "unplugged" for b in c.request("list")["boards"]),
             30, "soak unplugged")
    for t in (1, 2, 3):
        a = c.request("notify", board="soak", channel="tick", value=t)
        assert a["ok"], a
    bad = c.request("notify", board="soak", channel="tick", value=-1)
    assert not bad["ok"] and bad["error"] == "InvalidValue", bad
    soak.start()

    def read(ch: str) -> int:
        r = c.request("read", board="soak", channel=ch)
        return int(r["value"]) if r["ok"] else -1
    wait_for(lambda: read("tick_last") == 3, 30, "tick 3 applied")
    assert [read(ch) for ch in ("ticks", "tick_first", "tick_twice", "tick_gaps")] == [3, 1, 0, 0]
    c.close()


def test_events_resume_points(serve: Serve, soak: Emulator) -> None:
    """``last``, ``after``, ``reset`` and unknown names, as docs/SERVICE.md describes them."""
    c = ready_client(serve, "soak")
    a = c.request("events", board="soak", names=[], sub=1, after=0)
    assert a["ok"] and a["last"] == 0 and a["missed"] == 0, a
    assert c.request("call", board="soak", channel="selftest", arg=2)["value"] == 2
    wait_for(lambda: c.drain(time.monotonic() + 0.1) or len(c.events) == 2, 10, "2 events")
    assert [(e["id"], e["value"]) for e in c.events] == [(1, True), (2, False)]
    c.close()
    c = Raw(serve.socket)
    a = c.request("events", board="soak", names=["bumper"], sub=1, after=1)
    assert a["ok"] and a["last"] == 2 and a["missed"] == 0 and not a.get("reset"), a
    assert [e["id"] for e in c.events] == [2], "only what came after id 1"
    b = c.request("events", board="soak", names=[], sub=2)
    assert b["ok"] and b["last"] == 2 and "missed" not in b and [e["id"] for e in c.events] == [2], \
        "without after: from the next event on"
    r = c.request("events", board="soak", names=[], sub=3, after=99)
    assert r["ok"] and r["reset"] is True and [e["id"] for e in c.events] == [2, 1, 2], \
        "after beyond every id: the store was wiped, everything kept is sent"
    bad = c.request("events", board="soak", names=["nope"], sub=4)
    assert not bad["ok"] and bad["error"] == "UnknownChannel", bad
    bad = c.request("events", board="soak", names=[], sub=5, after="x")
    assert not bad["ok"], bad
    c.close()
