#!/usr/bin/env python3
"""Row 4: hub decode throughput: hubwire's FrameDecoder vs pymavlink and pySerialTransfer.

Runs in the bench venv (build/bench-venv: pymavlink, pySerialTransfer, cobs, pyserial from PyPI),
never in .venv. All three parse the same realistic mix of telemetry, fed in 4096-byte reads as a
serial reader thread gets them; rounds are interleaved and the best round of each is kept, so the
ratios come from one run on the same machine state.

    build/bench-venv/bin/python bench/throughput.py [--seconds 1.0] [--rounds 3]
"""
from __future__ import annotations

import argparse
import cProfile
import io
import platform
import pstats
import random
import struct
import time

from common import md_table, row, save

from hubwire.wire import messages as m
from hubwire.wire.frame import FrameDecoder, encode_frame
from hubwire.wire.values import codec_for

N_FRAMES = 50_000
READ = 4096
IMU = {"t": "struct", "f": [{"n": "ax", "t": "f32"}, {"n": "ay", "t": "f32"}, {"n": "az", "t": "f32"},
                            {"n": "gyro", "t": "i16", "c": 3}]}


def telemetry(rng: random.Random):
    """The mix: 60 % imu samples (6 values), 30 % f32 samples, 5 % u16 responses, 5 % heartbeats."""
    out = []
    for i in range(N_FRAMES):
        r = rng.random()
        if r < 0.6:
            out.append(("imu", i, (rng.uniform(-2, 2), rng.uniform(-2, 2), 9.81 + rng.uniform(-.1, .1),
                                   rng.randrange(-500, 500), rng.randrange(-500, 500), rng.randrange(-500, 500))))
        elif r < 0.9:
            out.append(("f32", i, (rng.uniform(-1, 1),)))
        elif r < 0.95:
            out.append(("u16", i, (rng.randrange(7000, 7400),)))
        else:
            out.append(("hb", i, (i & 0xFFFF, 250, 0, 0, 0)))
    return out


def values_in(items) -> int:
    return sum(len(v) for _, _, v in items)


# --------------------------------------------------------------------------- hubwire

def hubwire_stream(items) -> bytes:
    imu, f32, u16 = codec_for(IMU), codec_for({"t": "f32"}), codec_for({"t": "u16"})
    parts = []
    for kind, i, v in items:
        if kind == "imu":
            parts.append(encode_frame(m.SAMPLE, i & 0xFF, 3, m.Sample(20, imu.encode(imu.decode(
                struct.pack("<fffhhh", *v)))).pack()))
        elif kind == "f32":
            parts.append(encode_frame(m.SAMPLE, i & 0xFF, 1, m.Sample(20, f32.encode(v[0])).pack()))
        elif kind == "u16":
            parts.append(encode_frame(m.RESPONSE, i & 0xFF, 5, u16.encode(v[0])))
        else:
            parts.append(encode_frame(m.HEARTBEAT, i & 0xFF, 0, m.Heartbeat(*v).pack()))
    return b"".join(parts)


def hubwire_framing(chunks) -> int:
    d = FrameDecoder(255)
    n = 0
    for c in chunks:
        n += len(d.feed(c))
    assert d.crc == d.overflow == d.dropped == 0
    return n


def make_hubwire_typed():
    """Framing + typed values, the way the hub's reader handles D / r / H frames (no threads)."""
    imu, f32, u16 = codec_for(IMU), codec_for({"t": "f32"}), codec_for({"t": "u16"})
    by_id = {3: imu, 1: f32}
    unpack_sample = m.Sample.unpack
    unpack_hb = m.Heartbeat.unpack

    def run(chunks) -> int:
        d = FrameDecoder(255)
        vals = 0
        sink = None
        for c in chunks:
            for f in d.feed(c):
                t = f.type
                if t == m.SAMPLE:
                    s = unpack_sample(f.payload)
                    sink = by_id[f.id].decode(s.value)
                    vals += 6 if f.id == 3 else 1
                elif t == m.RESPONSE:
                    sink = u16.decode(f.payload)
                    vals += 1
                elif t == m.HEARTBEAT:
                    sink = unpack_hb(f.payload)
                    vals += 5
        del sink
        return vals
    return run


# --------------------------------------------------------------------------- pymavlink

def mavlink_stream(items) -> bytes:
    from pymavlink.dialects.v20 import common as mav2
    mav = mav2.MAVLink(None, srcSystem=1, srcComponent=1)
    parts = []
    for kind, i, v in items:
        if kind == "imu":
            msg = mav2.MAVLink_scaled_imu_message(i, int(v[0] * 100), int(v[1] * 100), int(v[2] * 100),
                                                  v[3], v[4], v[5], 0, 0, 0, 0)
        elif kind == "f32":
            msg = mav2.MAVLink_named_value_float_message(i, b"left", v[0])
        elif kind == "u16":
            msg = mav2.MAVLink_named_value_int_message(i, b"battery", v[0])
        else:
            msg = mav2.MAVLink_heartbeat_message(2, 3, 0, 0, 4, 3)
        parts.append(msg.pack(mav))
        mav.seq = (mav.seq + 1) % 256
    return b"".join(parts)


def make_mavlink():
    from pymavlink.dialects.v20 import common as mav2

    def run(chunks) -> int:
        mav = mav2.MAVLink(None)
        n = 0
        for c in chunks:
            msgs = mav.parse_buffer(c)
            if msgs:
                n += len(msgs)
        assert mav.total_receive_errors == 0, mav.total_receive_errors
        return n
    return run


# --------------------------------------------------------------------------- pySerialTransfer

class _FakePort:
    """Just enough of serial.Serial for SerialTransfer.available(): the bytes come from memory."""

    is_open = True

    def __init__(self) -> None:
        self.buf = b""
        self.pos = 0

    def load(self, data: bytes) -> None:
        self.buf, self.pos = data, 0

    @property
    def in_waiting(self) -> int:
        return len(self.buf) - self.pos

    def read(self, n: int = 1) -> bytes:
        b = self.buf[self.pos:self.pos + n]
        self.pos += len(b)
        return b

    def open(self) -> None:
        pass


def serialtransfer_stream(items) -> bytes:
    from pySerialTransfer import pySerialTransfer as pst
    tx = pst.SerialTransfer(None, restrict_ports=False, debug=False)
    out = io.BytesIO()

    class W:
        is_open = True

        def write(self, b):
            out.write(bytes(b))

    tx.connection = W()
    for kind, i, v in items:
        if kind == "imu":
            payload, pid = struct.pack("<Hfffhhh", 20, *v), 3
        elif kind == "f32":
            payload, pid = struct.pack("<Hf", 20, *v), 1
        elif kind == "u16":
            payload, pid = struct.pack("<H", *v), 5
        else:
            payload, pid = struct.pack("<HHHHH", *v), 0
        for j, b in enumerate(payload):
            tx.tx_buff[j] = b
        tx.send(len(payload), packet_id=pid)
    return out.getvalue()


def make_serialtransfer():
    from pySerialTransfer import pySerialTransfer as pst
    rx = pst.SerialTransfer(None, restrict_ports=False, debug=False)
    port = _FakePort()
    rx.connection = port
    bad = (pst.Status.CRC_ERROR, pst.Status.PAYLOAD_ERROR, pst.Status.STOP_BYTE_ERROR)
    fmts = {3: struct.Struct("<Hfffhhh"), 1: struct.Struct("<Hf"), 5: struct.Struct("<H"), 0: struct.Struct("<HHHHH")}

    def run(chunks) -> int:
        n = 0
        for c in chunks:
            port.load(c)
            while port.in_waiting:
                got = rx.available()
                if got:
                    fmts[rx.id_byte].unpack(bytes(rx.rx_buff[:got]))  # typed values, as rx_obj would
                    n += 1
                elif rx.status in bad:
                    raise RuntimeError(f"SerialTransfer error {rx.status}")
        return n
    return run


# --------------------------------------------------------------------------- main

def chunked(data: bytes):
    return [data[i:i + READ] for i in range(0, len(data), READ)]


def best_rate(fn, chunks, seconds: float) -> float:
    """Units per second of fn(chunks) (fn returns units per pass), repeated for about ``seconds``."""
    units = 0
    t0 = time.perf_counter()
    while True:
        units += fn(chunks)
        dt = time.perf_counter() - t0
        if dt >= seconds:
            return units / dt


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    import pymavlink  # noqa: F401 - fails early outside the bench venv
    import pySerialTransfer  # noqa: F401
    from importlib.metadata import version

    items = telemetry(random.Random(1))
    hw = hubwire_stream(items)
    mv = mavlink_stream(items)
    st = serialtransfer_stream(items)
    hw_chunks, mv_chunks, st_chunks = chunked(hw), chunked(mv), chunked(st)
    nvals = values_in(items)
    typed = make_hubwire_typed()
    mav = make_mavlink()
    stx = make_serialtransfer()
    assert hubwire_framing(hw_chunks) == N_FRAMES
    assert typed(hw_chunks) == nvals
    assert mav(mv_chunks) == N_FRAMES
    assert stx(st_chunks) == N_FRAMES
    res = {"hubwire framing": [], "hubwire framing + typed values": [], "pymavlink parse_buffer": [],
           "pySerialTransfer available()": []}
    for _ in range(a.rounds):
        res["hubwire framing"].append(best_rate(hubwire_framing, hw_chunks, a.seconds) * 1)
        res["hubwire framing + typed values"].append(best_rate(typed, hw_chunks, a.seconds) / nvals * N_FRAMES)
        res["pymavlink parse_buffer"].append(best_rate(mav, mv_chunks, a.seconds / 2))
        res["pySerialTransfer available()"].append(best_rate(stx, st_chunks, a.seconds / 2))
    best = {k: max(v) for k, v in res.items()}
    vps = best["hubwire framing + typed values"] * nvals / N_FRAMES
    fr = best["hubwire framing"]
    pm = best["pymavlink parse_buffer"]
    # ratios per round (both measured seconds apart on the same machine state), then the median
    per_round = sorted(h / p for h, p in zip(res["hubwire framing"], res["pymavlink parse_buffer"]))
    ratio = per_round[len(per_round) // 2]
    per_round_t = sorted(h / p for h, p in zip(res["hubwire framing + typed values"], res["pymavlink parse_buffer"]))
    ratio_typed = per_round_t[len(per_round_t) // 2]
    med_fr = sorted(res["hubwire framing"])[len(res["hubwire framing"]) // 2]

    # profile: where does the hubwire framing time go?
    pr = cProfile.Profile()
    pr.enable()
    for _ in range(3):
        hubwire_framing(hw_chunks)
    pr.disable()
    s = io.StringIO()
    pstats.Stats(pr, stream=s).sort_stats("tottime").print_stats(6)
    prof = "\n".join(line for line in s.getvalue().splitlines() if line.strip())[:2500]
    pr = cProfile.Profile()
    pr.enable()
    typed(hw_chunks)
    pr.disable()
    s = io.StringIO()
    pstats.Stats(pr, stream=s).sort_stats("tottime").print_stats(8)
    prof_t = "\n".join(line for line in s.getvalue().splitlines() if line.strip())[:3000]

    sizes = {"hubwire": len(hw), "MAVLink v2": len(mv), "SerialTransfer": len(st)}
    lines = [[k, f"{best[k] / 1e3:,.0f} k", f"{best[k] / pm:.1f}x",
              f"{' / '.join(f'{x / 1e3:,.0f}' for x in v)}"] for k, v in best.items() for v in [res[k]]]
    details = f"""### Row 4: hub decode throughput (Python {platform.python_version()}, one process, one run)

{N_FRAMES:,} frames of telemetry (60 % imu struct samples, 30 % f32 samples, 5 % u16 responses, 5 %
heartbeats; {nvals:,} typed values), fed in {READ}-byte reads. Equivalent MAVLink v2 stream (SCALED_IMU,
NAMED_VALUE_FLOAT, NAMED_VALUE_INT, HEARTBEAT; pymavlink {version('pymavlink')}, fastcrc
{'present' if _has('fastcrc') else 'absent'}) and SerialTransfer stream (same payloads; pySerialTransfer
{version('pySerialTransfer')}, a stub port object feeding `available()`). Stream sizes: {sizes}.
Rounds interleaved; best of {a.rounds}.

{md_table(["decoder", "frames/s (best)", "vs pymavlink", "k frames/s per round"], lines)}

hubwire typed values: **{vps / 1e6:.2f} M values/s**. pymavlink's frames/s already include decoding every
field into a message object. Median of the per-round ratios: hubwire framing is **{ratio:.1f}x** pymavlink,
framing + typed values **{ratio_typed:.1f}x**. Median framing round: {med_fr / 1e6:.2f} M frames/s (the
machine is shared: rounds differ by up to 1.5x; the best round is the least disturbed).

cProfile of hubwire framing (3 passes):

```
{prof}
```

cProfile of hubwire framing + typed values (1 pass): the per-frame Python objects dominate.

```
{prof_t}
```
"""
    rows = [
        row("4a. Hub framing throughput (FrameDecoder.feed)", ">= 1 M frames/s", f"{fr / 1e6:.2f} M frames/s (best round; median {med_fr / 1e6:.2f})",
            fr >= 1e6, "build/bench-venv/bin/python bench/throughput.py"),
        row("4b. Hub framing vs pymavlink parse_buffer (same run)", ">= 3x", f"{ratio:.1f}x "
            f"({ratio_typed:.1f}x with typed values: {vps / 1e6:.2f} M values/s)", ratio >= 3,
            "build/bench-venv/bin/python bench/throughput.py",
            f"pymavlink {pm / 1e3:,.0f} k frames/s; pySerialTransfer "
            f"{best['pySerialTransfer available()'] / 1e3:,.0f} k frames/s"),
    ]
    save("throughput", rows, details, {"best": best, "rounds": res})


def _has(mod: str) -> bool:
    try:
        __import__(mod)
        return True
    except ImportError:
        return False


if __name__ == "__main__":
    main()
