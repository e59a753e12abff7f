"""The dashboard's choices and records without a browser: widgets from descriptors, plot columns,
history windows, CSV, the token gate and the address check."""
from __future__ import annotations

import asyncio
import json
from typing import Any, Dict, List, MutableMapping, Tuple

import pytest

from hubwire.descriptor import parse_descriptor
from hubwire.dashboard import model
from hubwire.dashboard.auth import TOKEN_ENV, load_token, served_names
from hubwire.dashboard.server import TOKEN_COOKIE, TokenGate, is_loopback

DESC = {"p": 1, "n": "bot", "ch": [
    {"id": 1, "n": "speed", "a": "rws", "t": "f32", "min": -1, "max": 1, "u": "m/s"},
    {"id": 2, "n": "count", "a": "rw", "t": "u16"},
    {"id": 3, "n": "led", "a": "rw", "t": "bool"},
    {"id": 4, "n": "label", "a": "rw", "t": "str", "c": 8},
    {"id": 5, "n": "pose", "a": "rws", "t": "struct", "f": [{"n": "x", "t": "f32"}, {"n": "g", "t": "i16", "c": 2}]},
    {"id": 6, "n": "gains", "a": "w", "t": "u8", "c": 3},
    {"id": 7, "n": "half", "a": "w", "t": "i8", "min": 0},
]}


def channels() -> Dict[str, Any]:
    d = parse_descriptor(json.dumps(DESC).encode())
    return {c.name: c for c in d.channels}


def test_each_writable_gets_the_input_its_type_and_range_call_for() -> None:
    ch = channels()
    got = {n: model.widget_for(c) for n, c in ch.items()}
    assert got == {"speed": "slider", "count": "number", "led": "toggle", "label": "text", "pose": "json",
                   "gains": "json", "half": "number"}  # half has one end of a range only


def test_numbers_are_plotted_and_strings_are_not() -> None:
    ch = channels()
    assert [n for n, c in ch.items() if model.plottable(c)] == ["speed", "count", "led", "pose"]


def test_a_struct_is_plotted_as_one_column_per_number() -> None:
    rec = model.ChannelRecord(channels()["pose"], 10.0)
    rec.add({"x": 1.5, "g": [3, -4]}, at=100.0)
    rec.add({"x": 2.0, "g": [5, 6]}, at=100.5)
    assert rec.columns == ["pose.x", "pose.g[0]", "pose.g[1]"]
    times, rows = rec.window(10.0, now=101.0)
    assert rows == [(1.5, 3.0, -4.0), (2.0, 5.0, 6.0)]
    assert model.to_csv(rec.columns, times, rows).splitlines() == [
        "time,pose.x,pose.g[0],pose.g[1]", "100.000000,1.5,3,-4", "100.500000,2,5,6"]


def test_history_keeps_the_last_minutes_and_a_window_picks_from_it() -> None:
    rec = model.ChannelRecord(channels()["speed"], 10.0)
    for i in range(3000):
        rec.add(i / 1000.0, at=float(i))
    times, rows = rec.window(10.0, now=2999.0)
    assert times == [float(t) for t in range(2989, 3000)] and rows[-1] == (2.999,)
    times, rows = rec.window(1e6, now=2999.0)
    assert times[0] == 2999 - model.HISTORY_S and len(rows) == model.HISTORY_S + 1


def test_the_achieved_rate_counts_arrivals_in_its_window() -> None:
    rec = model.ChannelRecord(channels()["speed"], 10.0)
    for i in range(50):
        rec.add(0.0, at=10.0 + i * 0.1)  # 10 per second for 5 s
    assert rec.achieved(now=14.9) == pytest.approx(10.0, abs=0.5 + 1 / model.RATE_WINDOW_S)
    assert rec.achieved(now=14.9 + model.RATE_WINDOW_S + 0.01) == 0.0


def test_decimation_spreads_points_and_keeps_the_newest() -> None:
    times = [float(i) for i in range(1000)]
    idx = model.decimate(times, [(t,) for t in times], 100)
    assert len(idx) <= 101 and idx[0] == 0 and idx[-1] == 999 and idx == sorted(set(idx))
    assert model.decimate(times[:5], [(t,) for t in times[:5]], 100) == [0, 1, 2, 3, 4]


@pytest.mark.parametrize("host,loop", [("127.0.0.1", True), ("::1", True), ("localhost", True),
                                       ("127.5.0.1", True), ("0.0.0.0", False), ("192.168.1.4", False)])
def test_loopback_addresses(host: str, loop: bool) -> None:
    assert is_loopback(host) is loop


def test_a_token_is_made_unless_one_is_given_also_on_loopback(tmp_path: Any, monkeypatch: Any) -> None:
    monkeypatch.delenv(TOKEN_ENV, raising=False)
    made, fresh = load_token()
    assert fresh and len(made) >= 16 and made != load_token()[0]
    assert load_token("mine") == ("mine", False)
    monkeypatch.setenv(TOKEN_ENV, "from-env")
    assert load_token() == ("from-env", False) and load_token("mine") == ("mine", False)
    f = tmp_path / "t"
    f.write_text("from-file\nsecond line\n")
    assert load_token("mine", str(f)) == ("from-file", False)
    with pytest.raises(ValueError):
        load_token("two words")


def _call(gate: TokenGate, kind: str, query: bytes = b"", cookie: str = "") -> Tuple[List[Any], bool]:
    sent: List[MutableMapping[str, Any]] = []
    reached = []

    async def app(scope: Any, receive: Any, send: Any) -> None:
        reached.append(scope)
        await send({"type": "http.response.start", "status": 200, "headers": []})

    async def receive() -> MutableMapping[str, Any]:
        return {}

    async def send(msg: MutableMapping[str, Any]) -> None:
        sent.append(msg)

    gate.app = app
    headers = [(b"host", b"localhost:8080")] + ([(b"cookie", cookie.encode())] if cookie else [])
    asyncio.run(gate({"type": kind, "query_string": query, "headers": headers}, receive, send))
    return sent, bool(reached)


def test_the_token_gate_lets_in_only_who_gives_the_token() -> None:
    gate = TokenGate(None, "s3cret", served_names("127.0.0.1"))
    sent, reached = _call(gate, "http")
    assert not reached and sent[0]["status"] == 401
    sent, reached = _call(gate, "http", b"token=wrong")
    assert not reached and sent[0]["status"] == 401
    sent, reached = _call(gate, "websocket")
    assert not reached and sent[0] == {"type": "websocket.close", "code": 1008}
    sent, reached = _call(gate, "http", b"token=s3cret")
    assert reached and (b"set-cookie", f"{TOKEN_COOKIE}=s3cret; Path=/; HttpOnly; SameSite=Strict".encode()) \
        in sent[0]["headers"]
    sent, reached = _call(gate, "websocket", cookie=f"other=1; {TOKEN_COOKIE}=s3cret")
    assert reached
    sent, reached = _call(gate, "websocket", cookie=f"{TOKEN_COOKIE}=s3cre")
    assert not reached


def test_rates_from_the_command_line() -> None:
    from hubwire.dashboard.cli import parse_rates

    assert parse_rates([]) == (10.0, {})
    assert parse_rates(["1", "imu=100", "rover.left=50"]) == (1.0, {"imu": 100.0, "rover.left": 50.0})
    for bad in (["0"], ["imu=fast"], ["imu=2000"]):
        with pytest.raises(ValueError):
            parse_rates(bad)


def test_every_loss_seen_has_its_return_seen() -> None:
    """After a loss and the board's return the link line reads "1 time, back after ..." (a return by
    a reboot is a return too: the session's own counters said "link lost / restored 1 / 0")."""
    link = model.LinkRecord()
    link.observe("connecting", now=0.0)
    link.observe("ready", now=1.0)
    assert link.text() == "never"  # connecting at start is no loss
    link.observe("lost", now=10.0)
    link.observe("lost", now=11.0)
    assert (link.lost, link.text()) == (1, "1 time, lost now")
    link.observe("connecting", now=12.0)
    link.observe("ready", now=12.5)
    assert link.text() == "1 time, back after 2.5 s"
    link.observe("connecting", now=13.0)  # a reboot noticed while linked: it reads its description again
    link.observe("ready", now=13.2)
    assert link.text() == "1 time, back after 2.5 s"
    link.observe("unplugged", now=20.0)
    link.observe("ready", now=21.0)
    assert link.text() == "2 times, back after 1.0 s"


def test_several_channels_share_one_time_axis_in_the_csv() -> None:
    text = model.merge_csv([(["a"], [1.0, 3.0], [(1.0,), (3.5,)]), (["b[0]", "b[1]"], [2.0, 3.0], [(7.0, 8.0), (9.0, 1.0)])])
    assert text.splitlines() == ["time,a,b[0],b[1]", "1.000000,1,,", "2.000000,,7,8", "3.000000,3.5,,",
                                 "3.000000,,9,1"]


def test_the_plot_starts_with_streamed_numbers_and_tiles_show_single_numbers() -> None:
    ch = list(channels().values())
    assert model.default_picks(ch) == ["speed", "pose"]  # streamable numbers, no booleans
    assert model.key_channels(ch) == ["speed", "count", "led"]  # a unit first, then what is read


def test_refusals_are_said_in_plain_words() -> None:
    from hubwire.dashboard.words import NAK_WORDS, outcome
    from hubwire.errors import NakError
    from hubwire.wire.messages import NakCode

    for code in NakCode:
        text, name = outcome(NakError(int(code), "x"))
        assert name == code.name and code.name not in text and "NAK" not in text, text
    assert set(NAK_WORDS) == {c.name for c in NakCode}


def test_number_fields_say_the_range_in_words() -> None:
    """A number field shows the declared range in its label or placeholder, never as NiceGUI's
    min/max, which clamp a typed value (test_serve_dashboard_missions: 20 typed stays 20)."""
    from hubwire.dashboard.model import range_hint
    from hubwire.descriptor import parse_descriptor
    d = parse_descriptor(b'{"p":1,"n":"b","ch":[{"id":1,"n":"a","t":"f32","a":"rw","min":0.5,"max":10},'
                         b'{"id":2,"n":"c","t":"i16","a":"rw","min":-3},{"id":3,"n":"e","t":"u8","a":"rw"}]}')
    assert [range_hint(ch) for ch in d.channels] == ["0.5 to 10", "from -3", ""]
