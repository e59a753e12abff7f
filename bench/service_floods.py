"""Floods against `hubwire serve --mqtt` with an emulated Rover: what one misbehaving client costs.

Each flood runs for ``--seconds`` (default 10; ``--long``: 60) against a fresh service:

- ``subs``: one socket client asks for 20,000 event subscriptions while the board raises events;
- ``mqtt``: an MQTT client publishes malformed ``set`` commands as fast as it can;
- ``pipeline``: one socket client keeps 3,000 reads pipelined on the socket;
- ``huge``: an MQTT client publishes a 16 MB JSON value to a ``set`` and a ``descriptor`` topic
  every second;
- ``large``: an MQTT client publishes 1 MB JSON values (just under the bridge's packet limit) to a
  ``set`` and a ``descriptor`` topic as fast as it can.

Reported per flood: the service's peak RSS (from /proc, sampled every 50 ms) against its RSS before
the flood, the latency of a well-behaved socket client reading ``battery`` once every 100 ms
(median, worst, reads not answered within 10 s), and the failsafes the board fired (its
``failsafes`` channel: the hub went silent for more than 4 heartbeats).

    PYTHONPATH=host .venv/bin/python bench/service_floods.py [--seconds 10 | --long] [--only subs]

``--code DIR`` runs the service from another checkout's ``host`` (a before/after comparison).
"""
from __future__ import annotations

import argparse
import asyncio
import json
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from typing import Any, Dict, List

import aiomqtt

from common import ROOT, emulator

FLOODS = ("subs", "mqtt", "pipeline", "huge", "large")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def rss_mb(pid: int) -> float:
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return 0.0


class Peak(threading.Thread):
    def __init__(self, pid: int) -> None:
        super().__init__(daemon=True)
        self.pid, self.peak, self.stop = pid, 0.0, threading.Event()

    def run(self) -> None:
        while not self.stop.is_set():
            try:
                self.peak = max(self.peak, rss_mb(self.pid))
            except OSError:
                return
            time.sleep(0.05)


async def connect(path: str) -> Any:
    r, w = await asyncio.wait_for(asyncio.open_unix_connection(path, limit=1 << 22), 10)
    await asyncio.wait_for(r.readline(), 10)  # the greeting: a service whose loop is stuck sends none
    return r, w


async def request(path: str, req: Dict[str, Any], timeout: float = 10) -> Dict[str, Any]:
    r, w = await connect(path)
    try:
        w.write((json.dumps({"id": 1, **req}) + "\n").encode())
        while True:
            msg = json.loads(await asyncio.wait_for(r.readline(), timeout))
            if msg.get("id") == 1:
                return msg  # type: ignore[no-any-return]
    finally:
        w.close()


async def well_behaved(path: str, stop: asyncio.Event, lat: List[float]) -> int:
    """Reads once every 100 ms on a connection of its own; returns how many got no answer in 10 s."""
    r, w = await connect(path)
    missed, i = 0, 0
    while not stop.is_set():
        i += 1
        t0 = time.monotonic()
        w.write((json.dumps({"id": i, "op": "read", "board": "rover", "channel": "battery"}) + "\n").encode())
        try:
            while json.loads(await asyncio.wait_for(r.readline(), 10)).get("id") != i:
                pass
            lat.append(time.monotonic() - t0)
        except asyncio.TimeoutError:
            missed += 1
        await asyncio.sleep(0.1)
    w.close()
    return missed


async def drain(r: asyncio.StreamReader) -> int:
    n = 0
    try:
        while await r.readline():
            n += 1
    except (ValueError, ConnectionError):
        pass
    return n


async def flood_subs(path: str, port: int, stop: asyncio.Event) -> str:
    r, w = await connect(path)
    reader = asyncio.ensure_future(drain(r))
    w.write(b"".join((json.dumps({"id": i, "op": "events", "board": "rover", "sub": i}) + "\n").encode()
                     for i in range(20000)))
    rb, wb = await connect(path)
    calls = 0
    while not stop.is_set():
        calls += 1
        wb.write((json.dumps({"id": calls, "op": "call", "board": "rover", "channel": "selftest", "arg": 8})
                  + "\n").encode())
        try:
            await asyncio.wait_for(rb.readline(), 10)
        except asyncio.TimeoutError:
            pass
        await asyncio.sleep(0.05)
    w.close()
    wb.close()
    lines = await asyncio.wait_for(reader, 30)
    return f"{calls} selftest calls (8 events each); the flooder got {lines} lines"


async def flood_mqtt(path: str, port: int, stop: asyncio.Event) -> str:
    n = 0
    async with aiomqtt.Client("127.0.0.1", port, protocol=aiomqtt.ProtocolVersion.V5) as c:
        while not stop.is_set():
            for _ in range(100):
                await c.publish("hubwire/rover/set/left", b"not json %d" % n, qos=0)
                n += 1
            await asyncio.sleep(0)
    return f"{n} malformed set commands published"


async def flood_huge(path: str, port: int, stop: asyncio.Event) -> str:
    huge, n = b"[" + b"0," * 8_000_000 + b"0]", 0
    async with aiomqtt.Client("127.0.0.1", port, protocol=aiomqtt.ProtocolVersion.V5) as c:
        while not stop.is_set():
            await c.publish("hubwire/rover/set/left", huge, qos=1)
            await c.publish("hubwire/elsewhere/descriptor", huge, qos=1)
            n += 2
            await asyncio.sleep(1)
    return f"{n} JSON values of 16 MB published"


async def flood_large(path: str, port: int, stop: asyncio.Event) -> str:
    large, n = b"[" + b"0," * 500_000 + b"0]", 0
    async with aiomqtt.Client("127.0.0.1", port, protocol=aiomqtt.ProtocolVersion.V5) as c:
        while not stop.is_set():
            await c.publish("hubwire/rover/set/left", large, qos=1)
            await c.publish("hubwire/elsewhere/descriptor", large, qos=1)
            n += 2
    return f"{n} JSON values of 1 MB published"


async def flood_pipeline(path: str, port: int, stop: asyncio.Event) -> str:
    r, w = await connect(path)
    batches = answers = 0
    while not stop.is_set():
        batches += 1
        w.write(b"".join((json.dumps({"id": i, "op": "read", "board": "rover", "channel": "battery"})
                          + "\n").encode() for i in range(3000)))
        got = 0
        while got < 3000:
            try:
                line = await asyncio.wait_for(r.readline(), 60)
            except asyncio.TimeoutError:
                break
            if not line:
                break
            got += 1
        answers += got
    w.close()
    return f"{batches} batches of 3,000 pipelined reads, {answers} answered"


async def run_flood(name: str, args: argparse.Namespace, sock: str, port: int, pid: int) -> Dict[str, Any]:
    before = rss_mb(pid)
    fs0 = (await request(sock, {"op": "read", "board": "rover", "channel": "failsafes"}))["value"]
    peak = Peak(pid)
    peak.start()
    stop = asyncio.Event()
    lat: List[float] = []
    good = asyncio.ensure_future(well_behaved(sock, stop, lat))
    fl = asyncio.ensure_future({"subs": flood_subs, "mqtt": flood_mqtt, "pipeline": flood_pipeline,
                                "huge": flood_huge, "large": flood_large}[name](
        sock, port, stop))
    await asyncio.sleep(args.seconds)
    stop.set()
    note = await asyncio.wait_for(fl, 120)
    missed = await asyncio.wait_for(good, 60)
    peak.stop.set()
    try:
        fs1 = (await request(sock, {"op": "read", "board": "rover", "channel": "failsafes"}, 30))["value"]
    except (asyncio.TimeoutError, ConnectionError, KeyError):
        fs1 = None
    return {"flood": name, "seconds": args.seconds, "rss_before_mb": round(before, 1),
            "rss_peak_mb": round(peak.peak, 1), "reads": len(lat), "missed": missed,
            "p50_ms": round(1000 * statistics.median(lat), 1) if lat else None,
            "max_ms": round(1000 * max(lat), 1) if lat else None,
            "failsafes": None if fs1 is None else fs1 - fs0, "note": note}


def one(name: str, args: argparse.Namespace) -> Dict[str, Any]:
    d = tempfile.mkdtemp(prefix="hubwire-floods-")
    port = free_port()
    with open(os.path.join(d, "mosquitto.conf"), "w") as f:
        f.write(f"listener {port} 127.0.0.1\nallow_anonymous true\nmax_queued_messages 1000000\n")
    broker = subprocess.Popen([shutil.which("mosquitto") or "/usr/sbin/mosquitto", "-c", f.name],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.makedirs(os.path.join(d, "boards"))
    emu = emulator(os.path.join(d, "boards", "rover"))
    sock = os.path.join(d, "run", "hubwire.sock")
    env = dict(os.environ, HUBWIRE_SOCKET=sock, HUBWIRE_CACHE_DIR=os.path.join(d, "cache"),
               PYTHONPATH=os.path.join(args.code, "host"))
    serve = subprocess.Popen([sys.executable, "-m", "hubwire", "serve", "--no-usb", "--watch",
                              os.path.join(d, "boards", "*"), "--socket", sock, "--poll", "0.2",
                              "--mqtt", f"127.0.0.1:{port}", "--mqtt-id", "bench"],
                             stdout=subprocess.PIPE, stderr=open(os.path.join(d, "serve.log"), "w"), env=env)
    try:
        assert serve.stdout is not None and serve.stdout.readline().startswith(b"READY")

        async def go() -> Dict[str, Any]:
            for _ in range(200):
                try:
                    if (await request(sock, {"op": "read", "board": "rover", "channel": "battery"}))["ok"]:
                        break
                except (OSError, asyncio.TimeoutError, KeyError):
                    pass
                await asyncio.sleep(0.1)
            await asyncio.sleep(1)
            try:
                return await asyncio.wait_for(run_flood(name, args, sock, port, serve.pid), args.seconds + 180)
            except (asyncio.TimeoutError, OSError) as e:
                return {"flood": name, "seconds": args.seconds, "rss_before_mb": None,
                        "rss_peak_mb": round(rss_mb(serve.pid), 1), "reads": None, "missed": None, "p50_ms": None,
                        "max_ms": None, "failsafes": None,
                        "note": f"the service stopped answering ({type(e).__name__}): the flood never finished"}
        return asyncio.run(go())
    finally:
        serve.send_signal(signal.SIGTERM)
        try:
            serve.wait(20)
        except subprocess.TimeoutExpired:
            serve.kill()
        emu.stop()
        broker.terminate()
        broker.wait(10)
        shutil.rmtree(d, ignore_errors=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=10.0, help="how long each flood runs (default 10)")
    ap.add_argument("--long", action="store_true", help="60 s per flood")
    ap.add_argument("--only", action="append", choices=FLOODS, help="run only this flood (repeatable)")
    ap.add_argument("--code", default=ROOT, help="the checkout whose host/ runs the service (default this one)")
    args = ap.parse_args()
    if args.long:
        args.seconds = 60.0
    print("| flood | s | RSS before MB | RSS peak MB | reads | missed | p50 ms | max ms | failsafes | note |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in args.only or FLOODS:
        r = one(name, args)
        print("| " + " | ".join(str(r[k]) for k in ("flood", "seconds", "rss_before_mb", "rss_peak_mb", "reads",
                                                     "missed", "p50_ms", "max_ms", "failsafes", "note")) + " |",
              flush=True)


if __name__ == "__main__":
    main()
