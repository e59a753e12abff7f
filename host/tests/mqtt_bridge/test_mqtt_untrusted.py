"""Commands on the broker are untrusted: a reply goes only under the reply prefix, every bad payload
gets a typed error (never a traceback), and a flood of commands is bounded (docs/MQTT.md
"Security model" and "Limits"). Counts, not wall clock."""
from __future__ import annotations

import asyncio
import logging
import time
from typing import Any, List

import pytest

from hubwire.bridge import mqtt as bridge_mod

from .conftest import Broker
from .helpers import StandInFleet, running_bridge, watcher

#: every error type docs/MQTT.md lists for a command's reply ("Error" is for the unforeseen only)
TYPED = {"UnknownChannel", "NotWritable", "NotReadable", "NotCallable", "InvalidValue", "Nak", "Timeout",
         "LinkLost", "UnknownBoard", "NotStreamable", "BadRequest"}


def run(coro: Any, timeout: float = 90) -> Any:
    return asyncio.run(asyncio.wait_for(coro, timeout))


def _no_tracebacks(caplog: pytest.LogCaptureFixture) -> None:
    bad = [r for r in caplog.records if r.exc_info or "Traceback" in r.getMessage()]
    assert not bad, [r.getMessage() for r in bad]


def test_reply_to_outside_the_prefix_or_with_wildcards_is_refused(broker: Broker, emulators, cache_dir: str,  # type: ignore[no-untyped-def]
                                                                   caplog: pytest.LogCaptureFixture) -> None:
    emu, = emulators(1)
    caplog.set_level(logging.WARNING)
    loop_errors: List[Any] = []

    async def main() -> None:
        asyncio.get_running_loop().set_exception_handler(lambda _l, ctx: loop_errors.append(ctx))
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port):
            async with watcher(broker.port, "#") as w:
                bad = ["elsewhere/replies", "hubwire/#", "hubwire/+/x", "hubwire/a\u0000b", "hubwire/rover/set/left",
                       "$SYS/x", ""]
                for i, to in enumerate(bad):
                    env = {"op": "set", "channel": "left", "value": 0.25, "id": i, "reply_to": to}
                    await w.client.publish("hubwire/rover/rpc", __import__("json").dumps(env), qos=1)
                # the refusals reach the board's error topic, typed; nothing was written
                await w.wait_for(lambda: len(w.on("hubwire/rover/error")) >= len(bad) - 1, 15, "refusals")
                errs = w.on("hubwire/rover/error")
                assert {e["error"] for e in errs} == {"BadRequest"}, errs
                assert await w.request("hubwire/rover/read/left", "") == {"ok": True, "value": 0.0}
                assert not [t for t, _, _ in w.all if t.startswith(("elsewhere/", "$SYS"))]
                assert not [t for t, _, _ in w.all if t == "hubwire/rover/set/left"]
                # a reply topic under the prefix is fine
                env = {"op": "read", "channel": "battery", "id": "x", "reply_to": "hubwire/replies/me"}
                await w.client.publish("hubwire/rover/rpc", __import__("json").dumps(env), qos=1)
                await w.wait_for(lambda: w.on("hubwire/replies/me"), 10, "the reply")
                assert w.on("hubwire/replies/me") == [{"id": "x", "ok": True, "value": 7400}]
        await fleet.close()
    run(main())
    assert not loop_errors, loop_errors
    _no_tracebacks(caplog)
    assert any("BadRequest" in r.getMessage() for r in caplog.records)


def test_every_bad_payload_gets_a_typed_error(broker: Broker, emulators, cache_dir: str,  # type: ignore[no-untyped-def]
                                              caplog: pytest.LogCaptureFixture) -> None:
    emu, = emulators(1)
    caplog.set_level(logging.WARNING)
    cases = [
        ("hubwire/rover/set/left", b"\xff\xfe"),
        ("hubwire/rover/set/left", b"[" * 100000),
        ("hubwire/rover/set/left", b'{"a": 1}'),
        ("hubwire/rover/set/imu", b'{"ax": "x"}'),
        ("hubwire/rover/set/left", b"1e400"),
        ("hubwire/rover/call/beep", b'"abc"'),
        ("hubwire/rover/rpc", b"[" * 100000),
        ("hubwire/rover/rpc", b'{"op": "set", "channel": "left", "value": "x", "id": "\\udc80"}'),
        ("hubwire/rover/rpc", b'{"op": "set", "channel": 5}'),
        ("hubwire/rover/rpc", b'{"op": "subscribe", "channel": "imu", "value": {"hz": "x"}}'),
        ("hubwire/rover/subscribe/imu", b'{"hz": 5, "client": ' + b"[" * 50000 + b"}"),
        ("hubwire/rover/subscribe/imu", b"1e400"),
        ("hubwire/nobody/set/left", b"0.5"),
        ("hubwire/rover/set/nothing", b"0.5"),
    ]

    async def main() -> List[Any]:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        out = []
        async with running_bridge(fleet, broker.port):
            async with watcher(broker.port) as w:
                for topic, payload in cases:
                    try:
                        r = await w.request(topic, payload, timeout=15)
                    except asyncio.TimeoutError:
                        r = {"no reply": topic, "payload": payload[:20]}
                    out.append(r)
        await fleet.close()
        return out

    replies = run(main(), 180)
    for (topic, payload), r in zip(cases, replies):
        assert r.get("ok") is not True and r.get("error") in TYPED, (topic, payload[:20], r)
    _no_tracebacks(caplog)


def test_a_command_flood_is_bounded_and_counted(broker: Broker, emulators, cache_dir: str,  # type: ignore[no-untyped-def]
                                                caplog: pytest.LogCaptureFixture) -> None:
    emu, = emulators(1)
    caplog.set_level(logging.WARNING, logger="hubwire.mqtt")
    n = 5000
    cap = getattr(bridge_mod, "INBOUND_QUEUE", 256)
    burst = getattr(bridge_mod, "INBOUND_BURST", 100)
    rate = getattr(bridge_mod, "INBOUND_RATE_HZ", 100)

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port) as bridge:
            async with watcher(broker.port, "hubwire/rover/error") as w:
                t0 = time.monotonic()
                for i in range(n):
                    await w.client.publish("hubwire/rover/set/left", b"not json %d" % i, qos=0)
                # a well-behaved client is still answered (asking again when its command was dropped)
                for _ in range(30):
                    try:
                        r = await w.request("hubwire/rover/read/battery", "", timeout=2)
                        break
                    except asyncio.TimeoutError:
                        pass
                assert r == {"ok": True, "value": 7400}
                elapsed = time.monotonic() - t0
                inbound = getattr(bridge, "inbound", None)
                assert inbound is not None, "the bridge has no bounded inbound queue"
                assert inbound.peak <= cap
                assert inbound.dropped > 0
                assert inbound.accepted + inbound.dropped == inbound.received
                # the rate limit: at most the burst plus the rate for the time it took (plus the read)
                assert inbound.accepted <= burst + rate * (time.monotonic() - t0) + 1
                assert len(w.on("hubwire/rover/error")) <= inbound.accepted
                drops = [r for r in caplog.records if "dropped" in r.getMessage()]
                assert 1 <= len(drops) <= 1 + elapsed / bridge_mod.DROP_LOG_INTERVAL_S
        await fleet.close()
    run(main(), 240)


@pytest.mark.parametrize("topic", ["hubwire/elsewhere/descriptor", "hubwire/rover/set/left"])
def test_deeply_nested_json_is_refused_and_the_bridge_stays(broker: Broker, emulators,  # type: ignore[no-untyped-def]
                                                            cache_dir: str, topic: str) -> None:
    emu, = emulators(1)

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        await fleet.plug("rover", emu.link)
        async with running_bridge(fleet, broker.port) as bridge:
            async with watcher(broker.port, "hubwire/rover/error") as w:
                # nested deeper than Python's JSON decoder recurses: RecursionError, not ValueError
                await w.client.publish(topic, b"[" * 200_000, qos=1)
                await asyncio.sleep(0.5)
                assert await w.request("hubwire/rover/read/battery", "", timeout=10) == {"ok": True, "value": 7400}
                assert bridge.connections == 1, "the bridge lost its broker session over one message"
                if "/set/" in topic:  # the sender is told its value is no JSON
                    await w.wait_for(lambda: any(e.get("error") in TYPED for e in w.on("hubwire/rover/error")),
                                     10, "a typed error")
        await fleet.close()
    run(main(), 120)
