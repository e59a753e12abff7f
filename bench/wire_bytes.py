#!/usr/bin/env python3
"""Row 3: bytes on the wire per message kind, computed with the hub's own codec (hubwire.wire).

    python bench/wire_bytes.py
"""
from __future__ import annotations


from common import md_table, row, save

from hubwire.wire import messages as m
from hubwire.wire.frame import encode_frame
from hubwire.wire.values import codec_for

IMU = {"t": "struct", "f": [{"n": "ax", "t": "f32"}, {"n": "ay", "t": "f32"}, {"n": "az", "t": "f32"},
                            {"n": "gyro", "t": "i16", "c": 3}]}


def run() -> None:
    f32 = codec_for({"t": "f32"})
    imu = codec_for(IMU)
    imu_val = imu.decode(bytes(18))
    kinds = [
        ("hello `*`", m.HELLO, m.Hello(1, 0, 0x12345678, 255, 250).pack()),
        ("heartbeat `H`", m.HEARTBEAT, m.Heartbeat(7, 250, 0, 0, 0).pack()),
        ("descriptor chunk request `J`", m.CHUNK, m.ChunkRequest(0, 28).pack()),
        ("descriptor chunk `J` (28 B of JSON)", m.CHUNK, m.Chunk(0, 832, b"x" * 28).pack()),
        ("request `R`", m.REQUEST, b""),
        ("response `r` (f32)", m.RESPONSE, f32.encode(0.5)),
        ("response `r` (imu struct, 18 B)", m.RESPONSE, imu.encode(imu_val)),
        ("control `C` (bool)", m.CONTROL, b"\x01"),
        ("control `C` (f32)", m.CONTROL, f32.encode(0.5)),
        ("ACK", m.ACK, b""),
        ("ACK to `S` (granted interval)", m.ACK, m.SubscribeAck(20).pack()),
        ("NAK", m.NAK, m.Nak(4).pack()),
        ("event `!` (bool)", m.EVENT, b"\x01"),
        ("subscribe `S`", m.SUBSCRIBE, m.Subscribe(20).pack()),
        ("sample `D` (f32)", m.SAMPLE, m.Sample(20, f32.encode(0.5)).pack()),
        ("sample `D` (imu struct)", m.SAMPLE, m.Sample(20, imu.encode(imu_val)).pack()),
    ]
    lines = []
    overheads = set()
    for name, t, payload in kinds:
        n = len(encode_frame(t, 5, 3, payload))
        overheads.add(n - len(payload))
        lines.append([name, len(payload), n, n - len(payload)])
    big = len(encode_frame(m.SAMPLE, 5, 3, bytes(range(1, 251)))) - 250
    ov = max(overheads)
    details = f"""### Row 3: bytes on the wire per message kind (hubwire.wire.encode_frame)

{md_table(["message", "payload B", "wire B", "overhead B"], lines)}

Overhead per frame: **{ov} bytes** for every payload up to 249 bytes (3 header + 2 CRC + 1 COBS code +
1 delimiter; a 250-byte payload costs {big}). For scale: MAVLink v2 12 (unsigned), rosserial 8,
SerialComm 11 (figures from the issue, not measured here). A round trip `R` + `r` f32 is
{lines[4][2] + lines[5][2]} bytes; a control with its ACK {lines[8][2] + lines[9][2]} bytes; a 50 Hz imu stream
{lines[15][2] * 50} B/s = {lines[15][2] * 50 * 10 / 115200:.0%} of a 115200 link.
"""
    save("wire_bytes", [row("3. Overhead per frame on the wire", "7 B", f"{ov} B (payload <= 249 B)", ov <= 7,
                            "python bench/wire_bytes.py", "MAVLink v2 12, rosserial 8, SerialComm 11")], details)


if __name__ == "__main__":
    run()
