"""What one socket client can make `hubwire serve` hold: subscriptions, requests in flight and
answers waiting to be read are capped per client (docs/SERVICE.md "Limits"), and every malformed
request gets an answer of a documented type. Counts, not wall clock."""
from __future__ import annotations

import asyncio
import json
from typing import Any, Callable, Dict, List, Tuple

from conftest import Emulator
from hubwire.daemon import server as srv

from .conftest import Serve

#: the caps of hubwire.daemon.server (values in force when they did not exist yet, for the old code)
MAX_SUBSCRIPTIONS = getattr(srv, "MAX_SUBSCRIPTIONS", 256)
MAX_PENDING = getattr(srv, "MAX_PENDING", 64)


async def _open(path: str, limit: int = 1 << 22) -> Tuple[asyncio.StreamReader, asyncio.StreamWriter]:
    """A connection; its reader stops taking bytes from the socket beyond about 2 * ``limit``."""
    r, w = await asyncio.open_unix_connection(path, limit=limit)
    json.loads(await asyncio.wait_for(r.readline(), 10))  # the greeting
    return r, w


async def _answers(r: asyncio.StreamReader, n: int, timeout: float = 60) -> Dict[Any, Dict[str, Any]]:
    """Read until ``n`` answers (lines with an ``id``) came in; keyed by id."""
    out: Dict[Any, Dict[str, Any]] = {}
    while len(out) < n:
        line = await asyncio.wait_for(r.readline(), timeout)
        assert line, f"the service closed the connection after {len(out)} of {n} answers"
        msg = json.loads(line)
        if "id" in msg:
            assert msg["id"] not in out, f"two answers to {msg['id']}"
            out[msg["id"]] = msg
    return out


def test_malformed_requests_get_answers_of_documented_types(serve: Serve,
                                                             emulators: Callable[[str], Emulator]) -> None:
    emulators("a")
    serve.wait_state("rover", "ready")

    async def main() -> Dict[Any, Dict[str, Any]]:
        r, w = await _open(serve.socket)
        reqs: List[bytes] = [
            b'{"id": "\\udc80", "op": "list"}\n',  # a lone surrogate: valid JSON, not encodable as UTF-8
            b'{"id": 2, "op": "write", "board": "rover", "channel": "left", "raw": "zz"}\n',
            b'{"id": 3, "op": "stream", "board": "rover", "channel": "imu", "interval_ms": "abc", "sub": 1}\n',
            b'{"id": 4, "op": "events", "board": "rover", "sub": [1, 2]}\n',
            b'{"id": 5, "op": "read", "board": "rover", "channel": "left", "timeout": 1e400}\n',
            b'{"id": 6, "op": "events", "board": "rover", "names": 5, "sub": 9}\n',
            b'{"id": 7, "op": "list"}\n',
        ]
        w.write(b"".join(reqs))
        got = await _answers(r, len(reqs), 30)
        w.close()
        return got

    got = asyncio.run(main())
    assert got["\udc80"]["ok"] is True
    assert got[2]["error"] == "InvalidValue", got[2]
    assert got[3]["error"] == "Usage", got[3]
    assert got[4]["error"] == "Usage", got[4]
    assert got[6]["error"] == "Usage", got[6]
    assert got[7]["ok"] is True
    assert all(m.get("error") != "Error" for m in got.values()), got
    assert "Traceback" not in serve.log_text()


def test_subscriptions_per_client_are_capped(serve: Serve, emulators: Callable[[str], Emulator]) -> None:
    emulators("a")
    serve.wait_state("rover", "ready")
    n = MAX_SUBSCRIPTIONS + 20

    async def main() -> Tuple[int, List[Dict[str, Any]], int]:
        r, w = await _open(serve.socket)
        w.write(b"".join(json.dumps({"id": i, "op": "events", "board": "rover", "sub": i}).encode() + b"\n"
                         for i in range(n)))
        got = await _answers(r, n)
        refused = [m for m in got.values() if not m["ok"]]
        # one unsubscribed frees a place
        w.write(b'{"id": "u", "op": "unsubscribe", "sub": 0}\n{"id": "again", "op": "events", "board": "rover", '
                b'"sub": "again"}\n')
        more = await _answers(r, 2)
        w.close()
        return sum(1 for m in got.values() if m["ok"]), refused, more["again"]["ok"]

    ok, refused, again = asyncio.run(main())
    assert ok == MAX_SUBSCRIPTIONS
    assert len(refused) == 20 and {m["error"] for m in refused} == {"Busy"}, refused[:2]
    assert str(MAX_SUBSCRIPTIONS) in refused[0]["message"]
    assert again is True


def test_pipelined_reads_do_not_make_another_client_wait_for_all_of_them(
        serve: Serve, emulators: Callable[[str], Emulator]) -> None:
    """One client pipelines 3,000 reads; a second client's read is answered while most of the
    first one's are still to come (requests in flight per client are capped, and the board's
    queue serves the clients in turn)."""
    emulators("a")
    serve.wait_state("rover", "ready")
    n = 3000

    async def main() -> int:
        ra, wa = await _open(serve.socket)
        rb, wb = await _open(serve.socket)
        wa.write(b"".join(json.dumps({"id": i, "op": "read", "board": "rover", "channel": "battery"}).encode()
                          + b"\n" for i in range(n)))
        await wa.drain()
        seen = 0
        first = json.loads(await asyncio.wait_for(ra.readline(), 60))
        assert first.get("ok") is True, first
        seen += 1
        wb.write(b'{"id": "b", "op": "read", "board": "rover", "channel": "battery"}\n')
        b_task = asyncio.ensure_future(_answers(rb, 1, 120))
        while not b_task.done():
            line = await asyncio.wait_for(ra.readline(), 60)
            assert line
            seen += 1
        assert (await b_task)["b"]["value"] == 7400
        at_b = seen
        rest = await _answers(ra, n - seen)  # every request is still answered, once
        assert all(m["ok"] for m in rest.values())
        wa.close()
        wb.close()
        return at_b

    at_b = asyncio.run(main())
    # the second client waited for at most a few rounds of the first one's cap, not for all of them
    assert at_b <= 4 * MAX_PENDING, f"the second client's read waited for {at_b} of the first one's"


def test_a_client_that_does_not_read_is_disconnected_with_a_reason(serve: Serve,
                                                                    emulators: Callable[[str], Emulator]) -> None:
    """Answers wait for the client to read them (one client's requests in flight are capped);
    what the service pushes unasked (events, samples) cannot: beyond MAX_BACKLOG bytes the client
    is told why and disconnected."""
    emulators("a")
    serve.wait_state("rover", "ready")
    subs = min(MAX_SUBSCRIPTIONS, 64)
    events = 600  # each pushed to every subscription: far more bytes than the cap

    async def main() -> Tuple[int, Dict[str, Any], int]:
        r, w = await _open(serve.socket, limit=4096)
        w.write(b"".join(json.dumps({"id": i, "op": "events", "board": "rover", "sub": i}).encode() + b"\n"
                         for i in range(subs)))
        assert all(m["ok"] for m in (await _answers(r, subs)).values())
        # now this client stops reading; another one makes the board raise events
        rb, wb = await _open(serve.socket)
        raised, i = 0, 0
        while raised < events and i < 20 * events:
            wb.write(json.dumps({"id": i, "op": "call", "board": "rover", "channel": "selftest",
                                 "arg": 8}).encode() + b"\n")
            got = await _answers(rb, 1)
            raised += int(got[i]["value"])
            i += 1
        wb.close()
        pushed, last = 0, {}
        while True:
            line = await asyncio.wait_for(r.readline(), 30)
            if not line:
                break
            last = json.loads(line)
            pushed += "event" in last
        w.close()
        return pushed, last, raised

    pushed, last, raised = asyncio.run(main())
    assert raised >= events
    assert pushed < raised * subs
    assert last.get("error") == "Overflow" and "disconnected" in last.get("message", ""), last
    # the service is still there for others
    assert serve.cli("get", "rover", "battery").stdout.strip() == "7400"
