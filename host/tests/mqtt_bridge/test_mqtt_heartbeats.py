"""No MQTT client can starve the boards' heartbeats (docs/MQTT.md "Limits"): during a flood of
commands, small and malformed or huge and well-formed, the hub's heartbeats keep reaching the board
within its link-loss bound (4 of the hub's intervals). Measured by the board: its ``failsafes``
counter counts every time it heard nothing from the hub for that long."""
from __future__ import annotations

import asyncio
import logging
import time
from typing import Any

import aiomqtt

from hubwire.bridge import mqtt as bridge_mod
from hubwire.bridge.inbound import Inbound
from hubwire.bridge.mqtt import Bridge
from hubwire.bridge.topics import BridgeConfig

from .conftest import Broker
from .helpers import StandInFleet, running_bridge

#: the flood's length: 4 link-loss bounds of the default 250 ms heartbeat, many times over
FLOOD_S = 8.0
#: a well-formed JSON value far larger than any command: parsing it takes the loop a second or more
HUGE = b"[" + b"0," * 8_000_000 + b"0]"


def run(coro: Any, timeout: float = 240) -> Any:
    return asyncio.run(asyncio.wait_for(coro, timeout))


async def flood(port: int, seconds: float) -> int:
    """Malformed `set` commands as fast as one client can, and a huge one to a command topic and a
    descriptor topic every second; returns how many were published."""
    n = 0
    async with aiomqtt.Client("127.0.0.1", port, protocol=aiomqtt.ProtocolVersion.V5) as c:
        end = next_huge = time.monotonic()
        end += seconds
        while time.monotonic() < end:
            if time.monotonic() >= next_huge:
                next_huge += 1.0
                await c.publish("hubwire/rover/set/left", HUGE, qos=1)
                await c.publish("hubwire/elsewhere/descriptor", HUGE, qos=1)
                n += 2
            for _ in range(50):
                await c.publish("hubwire/rover/set/left", b"not json %d" % n, qos=0)
                n += 1
            await asyncio.sleep(0.005)
    return n


def test_a_command_flood_does_not_starve_the_heartbeats(broker: Broker, emulators,  # type: ignore[no-untyped-def]
                                                       cache_dir: str) -> None:
    emu, = emulators(1)

    async def main() -> None:
        fleet = StandInFleet(cache_dir)
        board = await fleet.plug("rover", emu.link)
        dev = board.device
        assert dev is not None
        async with running_bridge(fleet, broker.port) as bridge:
            before = await dev.read("failsafes")
            lost_before = dev.core.stats.link_lost
            published = await flood(broker.port, FLOOD_S)
            # whatever the bridge still holds is handled before the board is asked
            await asyncio.sleep(2.0)
            after = await dev.read("failsafes")
            assert published > 100
            assert bridge.inbound.received > 0, "the flood never reached the bridge"
            # the board heard the hub within 4 heartbeat intervals all along (its own clock) ...
            assert after == before, f"the board fired its failsafe {after - before} times during the flood"
            # ... and the hub heard the board: its link was never declared lost
            assert dev.core.stats.link_lost == lost_before
        await fleet.close()
    run(main())


def test_a_packet_over_the_limit_is_dropped_unread(cache_dir: str) -> None:
    """The broker is asked to keep larger packets from the bridge; one that comes anyway (a broker
    that ignores MQTT 5 Maximum Packet Size) is counted and dropped before any of it is parsed."""
    async def main() -> None:
        bridge = Bridge(StandInFleet(cache_dir), "127.0.0.1", 1, BridgeConfig(service_id="test"))
        over = b"{\"service\": \"other\"}" + b" " * bridge_mod.MAX_PACKET
        bridge._on_message(aiomqtt.Message("hubwire/elsewhere/descriptor", over, 0, False, 1, None))
        bridge._on_message(aiomqtt.Message("hubwire/rover/set/left", over, 0, False, 2, None))
        assert bridge.oversized == 2
        assert bridge.elsewhere == {} and bridge.inbound.received == 0
        # one byte less is taken: the descriptor names its service
        bridge._on_message(aiomqtt.Message("hubwire/elsewhere/descriptor", over[:bridge_mod.MAX_PACKET], 0, False,
                                           3, None))
        assert bridge.oversized == 2 and bridge.elsewhere == {"elsewhere": "other"}
    run(main(), 30)


def test_large_commands_cost_tokens_by_size_and_queued_bytes_are_bounded() -> None:
    """A 1 MiB command costs as many tokens as 65 small ones, and the queue holds at most
    ``max_bytes`` of payload: parsing what is taken stays bounded however large the commands."""
    now = [0.0]
    q: "Inbound[int]" = Inbound(256, 200.0, 200, 10.0, logging.getLogger("test"), clock=lambda: now[0],
                                bytes_per_token=16 * 1024, max_bytes=3 << 20)
    taken = sum(q.offer(i, 1 << 20) for i in range(10))
    assert taken == 3  # 200 tokens, 65 each
    assert q.bytes == 3 << 20 and q.dropped == 7
    now[0] += 10.0  # the bucket is full again, but the queue holds max_bytes already
    assert not q.offer(99, 1)
    assert q.offer(100, 0)  # a command without payload still fits
    assert not q.charge(1 << 30)  # more than the whole bucket
    assert q.charge(1 << 20)
