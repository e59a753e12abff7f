"""Hub channels against a scripted device: the bind report, the device's R / C / J answered by the
hub, exactly-once device writes and calls, hub events in order, the hub's descriptor, health."""
from __future__ import annotations

import contextlib
import struct
import threading
from typing import Any, Iterator, List, Tuple

import pytest

import hubwire
from hubwire import HubChannelError, HubChannels
from hubwire.descriptor import parse_descriptor
from hubwire.hub import bind_status
from hubwire.wire import messages as m
from hubwire.wire.messages import NakCode

from hubdevice import DESCRIPTOR, HubDevice, connect, f32, full_hub, wait_for


# ------------------------------------------------------------------------------ declarations


def test_types_come_from_values_and_annotations() -> None:
    hub = HubChannels()
    assert hub.provide("a", 1.5).channel.type_name == "f32"
    assert hub.provide("b", True).channel.type_name == "bool"
    assert hub.provide("c", lambda: 3, type="i16[3]").channel.type_name == "i16[3]"

    def now() -> int:
        return 1
    assert hub.provide("d", now).channel.type_name == "i32"
    ch = hub.action("e", lambda: None)
    assert ch.channel.type_name == "() -> void"

    def f(label: str) -> float:  # str has no capacity: explicit types needed
        return 0.0
    with pytest.raises(HubChannelError, match="no wire type for <class 'str'>"):
        hub.action("f", f)
    assert "f" not in hub
    assert hub.action("f", f, type="str[12]").channel.type_name == "(str[12]) -> f32"
    seen: List[float] = []

    @hub.accept("i")
    def on_i(value: float) -> None:  # the type from the handler's annotation
        seen.append(value)
    assert hub["i"].channel.type_name == "f32" and hub["i"].on_write is on_i and hub["i"].access == "w"
    hub.accept("j", type="u8", min=1, max=9)(seen.append)  # declared, then a handler given
    assert hub["j"].on_write == seen.append and hub["j"].channel.range == (1, 9)
    with pytest.raises(hubwire.InvalidValue, match="outside"):
        hub.provide("k", 12, type="u8", max=10)
    with pytest.raises(HubChannelError, match="unknown type 'u9'"):
        hub.provide("g", 1, type="u9")
    with pytest.raises(HubChannelError, match="type="):
        hub.provide("h", "text")


def test_str_needs_a_capacity_and_hub_descriptor_parses() -> None:
    hub = HubChannels("home")
    with pytest.raises(HubChannelError, match="capacity"):
        hub.provide("name", "x", type="str")
    hub.provide("name", "x", type="str[8]")
    hub.event("mode", type="u8", doc="heating mode")
    d = parse_descriptor(hub.descriptor())
    assert [(c.id, c.name, c.access, c.type_name) for c in d.channels] == [(1, "name", "r", "str[8]"),
                                                                           (2, "mode", "e", "u8")]
    assert hub.descriptor_hash() == m.fnv1a32(hub.descriptor())
    assert HubChannels().descriptor() == b"" and HubChannels().descriptor_hash() == 0


def test_hub_list_ids_must_count_from_one() -> None:
    bad = DESCRIPTOR.replace(b'"id":2,"n":"report"', b'"id":7,"n":"report"')
    with pytest.raises(hubwire.DescriptorError, match="hub id must be 2"):
        parse_descriptor(bad)
    with pytest.raises(hubwire.DescriptorError, match="not streamable"):
        parse_descriptor(DESCRIPTOR.replace(b'"a":"r","t":"f32"}', b'"a":"rs","t":"f32"}', 2))


# ------------------------------------------------------------------------------------ binding


def test_bind_report_then_rebind_when_declared() -> None:
    with HubDevice() as dev, connect(dev) as d:
        assert wait_for(lambda: len(dev.binds) >= 1)
        assert dev.binds[0] == bytes([1, 2, 2, 2, 2, 2])  # nothing declared: all UNKNOWN_CHANNEL
        h = dev.hub_hello
        assert h is not None and (h.descriptor_hash, h.descriptor_length) == (0, 0)  # a hub without channels
        assert d.hub_binding() == {n: "UNKNOWN_CHANNEL" for n in ("setpoint", "report", "dock", "mode", "target")}
        d.provide("setpoint", 20.0)
        assert wait_for(lambda: dev.binds[-1] == bytes([1, 0, 2, 2, 2, 2]))
        d.event("mode", type="u8")
        assert wait_for(lambda: dev.binds[-1] == bytes([1, 0, 2, 2, 0, 2]))
        assert d.hub_binding()["mode"] == "ok" and d.hub_binding()["dock"] == "UNKNOWN_CHANNEL"


def test_bind_status_codes() -> None:
    expected = {c.name: c for c in parse_descriptor(DESCRIPTOR).hub}
    hub = HubChannels()
    hub.provide("setpoint", 1.0)
    hub.provide("dock", 1.0)                       # readable, but the device calls it
    hub.event("report", type="u8")                 # an event, but the device writes it
    hub.provide("target", 1, type="i16", writable=True)
    hub.accept("mode", type="u8")                  # the device expects an event
    codes = {n: bind_status(expected[n], hub.get(n)) for n in expected}
    assert codes == {"setpoint": 0, "dock": NakCode.NOT_WRITABLE, "report": NakCode.NOT_WRITABLE,
                     "target": 0, "mode": NakCode.UNKNOWN_CHANNEL}
    assert bind_status(expected["setpoint"], None) == NakCode.UNKNOWN_CHANNEL
    hub.provide("setpoint", 1.0, type="f64")
    assert bind_status(expected["setpoint"], hub.get("setpoint")) == NakCode.BAD_LENGTH
    hub.provide("setpoint", 1.0, writable=True)  # rw offers the r the device needs
    assert bind_status(expected["setpoint"], hub.get("setpoint")) == 0


def not_interleaved(controls: List[Any]) -> bool:
    """Every C the hub sent (a write, or a bind report) and its retries form one run: no other C
    between the first and the last send of one (seq, id)."""
    for key in set(controls):
        at = [i for i, c in enumerate(controls) if c == key]
        if any(c != key for c in controls[at[0]:at[-1] + 1]):
            return False
    return True


def test_bind_report_never_overlaps_an_application_write() -> None:
    # the device's duplicate detection remembers one C: a bind report between a write and its
    # retry would make the retry look new, so the report waits for the write to end
    with HubDevice() as dev, connect(dev, tries=4) as d:
        assert wait_for(lambda: len(dev.binds) == 1)
        dev.answer_controls = False
        result: List[Any] = []
        t = threading.Thread(target=lambda: result.append(pytest.raises(hubwire.Timeout, d.write, "level", 1)))
        t.start()
        assert wait_for(lambda: len(dev.controls) >= 2)  # the write is out, retried
        d.provide("setpoint", 2.0)                          # wants a new bind report
        t.join(5)
        assert wait_for(lambda: len(dev.binds) == 2)
        assert sum(1 for _, cid in dev.controls if cid == 2) == 4  # the write, sent 4 times
        assert not_interleaved(dev.controls)


def test_an_unanswered_bind_report_gives_way_to_application_writes() -> None:
    with HubDevice() as dev:
        dev.answer_binds = False
        with connect(dev, tries=3) as d:
            assert wait_for(lambda: len(dev.binds) >= 3)  # sent, retried with the same seq ...
            d.write("level", 7)                           # ... then the write gets its turn
            first = next(i for i, (_, cid) in enumerate(dev.controls) if cid == 2)
            assert first >= 3 and {cid for _, cid in dev.controls[:first]} == {0}
            assert not_interleaved(dev.controls)
            n = len(dev.binds)
            assert wait_for(lambda: len(dev.binds) > n)   # and the report is tried again later
            assert d.notifications_pending == 0 and d.session.stats.hub_events_delivered == 0


def test_missing_name_raises_at_connect() -> None:
    log: List[Any] = []
    hub = full_hub(log)
    hub.remove("dock")
    with HubDevice() as dev:
        with pytest.raises(HubChannelError, match="calls hub channel 'dock'"):
            connect(dev, hub=hub)


def test_type_mismatch_raises_at_declaration() -> None:
    with HubDevice() as dev, connect(dev) as d:
        with pytest.raises(HubChannelError, match="as f32, the hub declares it u8"):
            d.provide("setpoint", 3, type="u8")
        assert "setpoint" not in d.hub  # refused, not half-declared
        with pytest.raises(HubChannelError, match="receives events of hub channel 'mode'"):
            d.provide("mode", 1, type="u8")
        d.provide("setpoint", 3.0)
        assert d.hub["setpoint"].value == 3.0


# ------------------------------------------------------------------------ device transactions


def test_device_reads_writes_and_calls() -> None:
    log: List[Any] = []
    with HubDevice() as dev, connect(dev, hub=full_hub(log)) as d:
        assert wait_for(lambda: dev.binds == [bytes([1, 0, 0, 0, 0, 0])])
        a = dev.ask(m.REQUEST, 1)
        assert a is not None and a.type == m.RESPONSE and a.payload == f32(21.5)
        d.hub["setpoint"].value = 19.0
        assert dev.ask(m.REQUEST, 1).payload == f32(19.0)  # type: ignore[union-attr]
        a = dev.ask(m.CONTROL, 2, f32(20.5) + b"\x01")
        assert a is not None and a.type == m.ACK
        assert log == [("report", 20.5, True)] and d.hub["report"].value.temp == 20.5
        a = dev.ask(m.CONTROL, 3, f32(0.5))
        assert a is not None and (a.type, a.payload) == (m.RESPONSE, b"\x01")
        assert log[-1] == ("dock", 0.5)
        assert d.session.stats.device_reads == 2 and d.session.stats.device_writes == 1
        assert d.session.stats.device_calls == 1


@pytest.mark.parametrize("hub_id, t, payload, code", [
    (9, m.REQUEST, b"", NakCode.UNKNOWN_CHANNEL),
    (2, m.REQUEST, b"", NakCode.NOT_READABLE),
    (1, m.CONTROL, f32(1.0), NakCode.NOT_WRITABLE),
    (2, m.CONTROL, f32(1.0), NakCode.BAD_LENGTH),
    (2, m.CONTROL, f32(1.0) + b"\x02", NakCode.BAD_VALUE),
    (5, m.CONTROL, struct.pack("<h", 101), NakCode.OUT_OF_RANGE),
])
def test_device_transactions_refused(hub_id: int, t: int, payload: bytes, code: int) -> None:
    log: List[Any] = []
    with HubDevice() as dev, connect(dev, hub=full_hub(log)) as d:
        assert wait_for(lambda: len(dev.binds) == 1)
        a = dev.ask(t, hub_id, payload)
        assert a is not None and (a.type, a.payload) == (m.NAK, bytes((code,)))
        assert log == [] and d.hub["target"].value is None


def test_handler_refusing_or_raising_is_rejected() -> None:
    with HubDevice() as dev, connect(dev) as d:
        d.accept("target", lambda v: v != 13, type="i16")

        @d.action("dock")
        def dock(speed: float) -> bool:
            raise RuntimeError("no dock")
        assert wait_for(lambda: dev.binds and dev.binds[-1][5] == 0 and dev.binds[-1][3] == 0)
        assert dev.ask(m.CONTROL, 5, struct.pack("<h", 13)).payload == bytes((NakCode.REJECTED,))  # type: ignore[union-attr]
        assert d.hub["target"].value is None
        assert dev.ask(m.CONTROL, 5, struct.pack("<h", 12)).type == m.ACK  # type: ignore[union-attr]
        assert d.hub["target"].value == 12
        assert dev.ask(m.CONTROL, 3, f32(1.0)).payload == bytes((NakCode.REJECTED,))  # type: ignore[union-attr]


def test_device_write_retried_is_applied_once() -> None:
    calls: List[int] = []
    with HubDevice() as dev, connect(dev) as d:
        d.accept("target", calls.append, type="i16")
        assert wait_for(lambda: dev.binds and dev.binds[-1][5] == 0)
        a = dev.ask(m.CONTROL, 5, struct.pack("<h", 7), lose=2)  # two answers lost: sent 3 times
        assert a is not None and a.type == m.ACK
        assert calls == [7]
        assert d.session.stats.device_duplicates >= 2  # more when the machine is slow: still applied once
        # the same seq after another device transaction is a new write (PROTOCOL.md rule)
        seq = dev._seq
        dev.ask(m.REQUEST, 1)
        assert dev.ask(m.CONTROL, 5, struct.pack("<h", 7), seq=seq).type == m.ACK  # type: ignore[union-attr]
        assert calls == [7, 7]


@contextlib.contextmanager
def slow_dock(hold: float) -> Iterator[Tuple[HubDevice, hubwire.Device, threading.Event, List[float]]]:
    """The hub action `dock` (channel 3), bound by the device; its handler records the speed, then
    holds until the gate is set (at most `hold` s)."""
    gate = threading.Event()
    calls: List[float] = []
    with HubDevice() as dev, connect(dev) as d:
        @d.action("dock")
        def dock(speed: float) -> bool:
            calls.append(speed)
            gate.wait(hold)
            return True
        assert wait_for(lambda: dev.binds and dev.binds[-1][3] == 0)
        yield dev, d, gate, calls


def test_slow_handler_answers_once_when_done() -> None:
    with slow_dock(2) as (dev, _, gate, calls):
        threading.Timer(0.35, gate.set).start()
        a = dev.ask(m.CONTROL, 3, f32(2.0))  # retried while the handler runs: not run again
        assert a is not None and a.payload == b"\x01" and calls == [2.0]


def test_an_answer_the_device_gave_up_on_is_not_sent_late() -> None:
    """The device's own R, C, J go one at a time (PROTOCOL.md 4.4): once it sends a newer one it has
    given up on the earlier one, so a slow handler's answer to that one is dropped, not sent late,
    where (the device's counter having come round) it could meet a newer request of its seq and id."""
    with slow_dock(10) as (dev, d, gate, calls):
        assert dev.ask(m.CONTROL, 3, f32(2.0), tries=2) is None  # the device gives up meanwhile
        seq = dev._seq
        assert wait_for(lambda: calls == [2.0])
        assert dev.ask(m.REQUEST, 1) is not None  # a newer transaction, answered at once
        gate.set()
        stats = d.session.stats
        old = lambda: [f for f in dev.answers_seen if (f.seq, f.id) == (seq, 3)]  # noqa: E731
        assert wait_for(lambda: bool(old()) or getattr(stats, "device_answers_dropped", 0) == 1)
        assert old() == [] and calls == [2.0]


def test_device_downloads_hub_descriptor() -> None:
    with HubDevice() as dev, connect(dev, hub=full_hub([])) as d:
        assert wait_for(lambda: dev.hub_hello is not None and dev.hub_hello.descriptor_length > 0)
        data = b""
        while True:
            a = dev.ask(m.CHUNK, 0, m.ChunkRequest(len(data), 255).pack())
            assert a is not None and a.type == m.CHUNK
            c = m.Chunk.unpack(a.payload)
            assert len(c.data) <= dev.max_payload - 4
            data += c.data
            if len(data) >= c.total:
                break
        assert data == d.hub.descriptor()
        assert (m.fnv1a32(data), len(data)) == (dev.hub_hello.descriptor_hash, dev.hub_hello.descriptor_length)
        assert [c.name for c in parse_descriptor(data).channels] == ["setpoint", "report", "dock", "mode", "target"]
        past = dev.ask(m.CHUNK, 0, m.ChunkRequest(len(data) + 1, 8).pack())
        assert past is not None and past.payload == bytes((NakCode.BAD_OFFSET,))
