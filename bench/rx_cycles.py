#!/usr/bin/env python3
"""Row 2: AVR cycles to receive a frame, from the stream read to the dispatched value (and the reply).

Builds extras/bench/RxCycles for the Uno, runs it in `simuno --fast --cycles-log`, pairs the
GPIOR0 marks (k at the start of region k, k|0x80 at its end) and reports exact simavr cycle counts.
Every region runs three times where it can: the counts must agree (the simulation is deterministic).

    python bench/rx_cycles.py
"""
from __future__ import annotations

import os
import statistics
import subprocess

from common import OUT, ROOT, SIMUNO, build_sketch, md_table, row, save, tmp_link

F_CPU = 16_000_000
TARGET = 80  # cycles per wire byte of a whole control frame (row 2b)
RX_TARGET = 100  # cycles per data byte from the Stream into the frame buffer (row 2a)

# region -> (label, payload bytes of the frame fed to hub.update(), or None for a part measured alone)
REGIONS = {
    1: ("calibration (two marks, nothing between)", None),
    2: ("begin(): event ids set (the table is a constant)", None),
    3: ("hub hello -> link up + hello reply", 16),
    4: ("first update() after link-up (sends a heartbeat)", None),
    5: ("idle update(), nothing received", None),
    6: ("H heartbeat from the hub (10 B payload): no answer, no lookup", 10),
    7: ("stray ACK (empty payload)", 0),
    8: ("C led=1 (bool, ch 6) -> ACK", 1),
    9: ("C left=0.5 (f32 + range, ch 1) -> ACK", 4),
    10: ("C right=0.5 (f32 + range, ch 2) -> ACK", 4),
    11: ("R left (ch 1) -> r f32", 0),
    12: ("R applied (ch 12) -> r u32", 0),
    13: ("R imu (ch 3, struct 18 B) -> r", 0),
    14: ("C name=\"benchbot\" (str, ch 7) -> ACK", 9),
    15: ("C beep(100) (action u16 -> bool, ch 9) -> r", 2),
    16: ("C selftest(1) (action u8 -> u8, ch 10) -> r", 1),
    17: ("H with an 8 B payload (receive path only)", 8),
    18: ("H with a 32 B payload (receive path only)", 32),
    19: ("R battery (u16, ch 5) -> r", 0),
    28: ("R failsafes (u16, ch 11) -> r", 0),
    32: ("J descriptor chunk at offset 0 (28 B) -> chunk", 3),
    33: ("J descriptor chunk at offset total/2 -> chunk", 3),
    34: ("J descriptor chunk at offset total-28 -> chunk", 3),
    35: ("J descriptor chunks in order, 0..total (mean per chunk)", 3),
    20: ("part: FrameReceiver::feed() x 8 bytes of `C led=1` (COBS, CRC, checks)", None),
    21: ("part: crc16() over the 4 raw bytes of `C led=1`", None),
    22: ("part: FrameReceiver::feed() x 39 bytes (32 B payload)", None),
    23: ("part: crc16() over 35 bytes", None),
    24: ("part: 8 x portRead() -> Stream::read() (the read update() does)", None),
    25: ("part: 8 x Stream::read() on the stub stream alone", None),
    26: ("part: FrameWriter::send() of an empty ACK through the port", None),
    29: ("part: FrameWriter::send() of a 4 B `r` through the port", None),
    27: ("part: find(): one channel record copied from flash", None),
    30: ("UART: 100 bytes out at Serial.begin(115200), until TX complete", None),
    31: ("UART: 100 bytes out at Serial.begin(1000000), until TX complete", None),
}


def run() -> None:
    elf = build_sketch(os.path.join(ROOT, "extras/bench/RxCycles"), os.path.join(OUT, "RxCycles"),
                       "-I" + os.path.join(ROOT, "examples/Rover"))  # Rover's channels.h
    log = os.path.join(OUT, "rx_cycles.log")
    if os.path.exists(log):
        os.remove(log)
    link = tmp_link("rxcycles")
    cmd = [SIMUNO, elf, "--link", link, "--fast", "--cycles-log", log]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=120)
    entries = [tuple(int(x) for x in line.split()) for line in open(log)]

    starts: dict = {}
    cycles: dict = {}
    data = []
    i = 0
    while i < len(entries):
        v, c = entries[i]
        if v == 0xFE:
            data = [entries[i + 1][0], entries[i + 2][0]]
            i += 3
            continue
        if v == 0xFF:
            break
        if v & 0x80:
            k = v & 0x7F
            cycles.setdefault(k, []).append(c - starts.pop(k))
        else:
            starts[k := v] = c
        i += 1
    desc_len = data[0] | (data[1] << 8) if data else 0
    cal = cycles[1][0]
    for k, v in cycles.items():
        if k != 1:
            cycles[k] = [x - cal for x in v]
    spread = max(max(v) - min(v) for k, v in cycles.items() if k != 35)  # 35: different chunks
    steady = "identical" if spread == 0 else f"equal within {spread} cycles (data-dependent: the seq byte)"
    c = {k: statistics.median(v) for k, v in cycles.items()}
    if 35 in cycles:
        c[35] = statistics.mean(cycles[35])

    def wire(k: int) -> int:
        return REGIONS[k][1] + 7  # header 3 + CRC 2 + COBS code 1 + delimiter 1 (payload <= 249)

    lines = []
    for k, (label, pl) in REGIONS.items():
        if k == 1 or k not in c:
            continue
        if pl is None:
            lines.append([k, label, "", f"{c[k]:,.0f}", f"{c[k] / F_CPU * 1e6:,.1f}", ""])
        else:
            lines.append([k, label, wire(k), f"{c[k]:,.0f}", f"{c[k] / F_CPU * 1e6:,.1f}", f"{c[k] / wire(k):,.0f}"])

    # receive path per data byte: the heartbeats of 8 and 32 payload bytes (regions 17, 18) differ
    # only in length, and none of their payload bytes is zero. (Region 6's payload is mostly zeros,
    # each a COBS code byte on the slow path: a slope from it would understate a data byte's cost.)
    slope = (c[18] - c[17]) / (wire(18) - wire(17))
    feed_slope = (c[22] - c[20]) / (39 - 8)  # FrameReceiver alone, includes the CRC at the end
    crc_per_byte = c[23] / 35
    read_per_byte = c[24] / 8
    stub_per_byte = c[25] / 8
    pos_slope_u16 = (c[28] - c[19]) / (11 - 5)
    pos_slope_4b = (c[12] - c[11]) / (12 - 1)
    ctl = c[8]
    other = ctl - c[5] - c[24] - c[20] - c[26]
    uart115 = c[30] / 100
    uart1m = c[31] / 100
    # what the Arduino core programs: 115200 -> U2X, UBRR 16 -> 117647 baud; 1000000 -> U2X, UBRR 1
    exp115 = 10 / 117647 * F_CPU
    exp1m = 10 / 1_000_000 * F_CPU

    breakdown = md_table(["part of `C led=1` (8 wire bytes)", "cycles", "share", "measured by"], [
        ["update() fixed cost (millis(), timers, stream slots)", f"{c[5]:,.0f}", f"{c[5] / ctl:.0%}", "region 5"],
        ["reading 8 bytes: portRead() -> Stream::read() (one virtual call)", f"{c[24]:,.0f}",
         f"{c[24] / ctl:.0%}", "region 24 (stub stream alone: region 25)"],
        ["FrameReceiver::feed() x 8: COBS, checks and the CRC", f"{c[20]:,.0f}", f"{c[20] / ctl:.0%}",
         f"region 20 (CRC alone {c[21]:,.0f}: region 21)"],
        ["ACK: FrameWriter::send() (CRC, COBS, writes)", f"{c[26]:,.0f}", f"{c[26] / ctl:.0%}", "region 26"],
        ["dispatch: handle(), find(6) (one record from flash), check, store, onChange, reply bookkeeping",
         f"{other:,.0f}", f"{other / ctl:.0%}", "the rest of region 8"],
        ["**total**", f"{ctl:,.0f}", "100%", "region 8"],
    ])
    details = f"""### Row 2: AVR cycles to receive (simavr, exact)

`extras/bench/RxCycles` (Rover's 12 channels, default config) feeds frames from RAM through a
Stream into `hub.update()`; replies go to a Stream that only counts. Timer0's interrupt is off while
measuring. Cycles are simavr's `avr->cycle` between two GPIOR0 writes, minus the {cal}-cycle cost of
the marks. Repeated regions (3 runs, new seq each) gave counts {steady}. 16 MHz: 16 cycles = 1 us.

{md_table(["region", "what", "wire bytes", "cycles", "us", "cycles / wire byte"], lines)}

Derived:

- **receive path per wire byte** (slope between the 15- and 39-byte heartbeats, payload bytes non-zero, nothing dispatched):
  **{slope:.0f} cycles/byte**; of that, per byte: reading through `portRead()` -> `Stream`
  {read_per_byte:.0f} (the stub stream's own `read()` plus the loop: {stub_per_byte:.0f}), `FrameReceiver::feed()`
  {feed_slope:.0f} (COBS bookkeeping + the CRC at the delimiter; `crc16()` alone: {crc_per_byte:.1f}/byte),
  the rest is `update()`'s loop.
- **8-byte control frame, `C led=1`, including the ACK: {ctl:,.0f} cycles = {ctl / 8:,.0f} cycles per wire byte
  ({ctl / F_CPU * 1e6:,.0f} us)**. `C left=0.5` (11 wire bytes): {c[9]:,.0f} cycles = {c[9] / 11:,.0f}/byte.
- **channel position**: a channel later in the table costs {pos_slope_u16:.0f} cycles more per
  position (R u16 on ch 5 vs ch 11) / {pos_slope_4b:.0f} cycles (R 4-byte on ch 1 vs ch 12): `find(id)`
  copies the one record from flash, whatever the id ({c[27]:,.0f} cycles, region 27).
- **descriptor chunk**: asked out of order, a `J` costs {c[32]:,.0f} / {c[33]:,.0f} / {c[34]:,.0f} cycles
  (offset 0 / middle / end): the JSON is a flash constant, copied from the offset asked. Asked in
  order, as the hub does: {c[35]:,.0f} cycles per chunk on average (region 35), so the {desc_len}-byte descriptor ({-(-desc_len // 28)} chunks of 28 bytes)
  costs about {-(-desc_len // 28) * c[35] / F_CPU * 1e3:.0f} ms of device CPU per download.
- **begin()** with Rover's 12 channels: {c[2]:,.0f} cycles = **{c[2] / F_CPU * 1e3:.1f} ms** of boot time
  (it copies the table from flash and gives each event its id; the declarations were checked and
  the descriptor hashed when the sketch compiled).

Breakdown of the control frame:

{breakdown}

UART timing in simavr (does simuno model the baud rate?): 100 bytes written to UDR0, waiting for
TX complete: {uart115:,.0f} cycles/byte at 115200 (the core programs U2X/UBRR 16 = 117647 baud:
10 bits = {exp115:,.0f} cycles) and {uart1m:,.0f} cycles/byte at 1000000 (10 bits = {exp1m:,.0f} cycles).
So **simavr does model the baud rate** (it derives a per-byte time from UBRR/U2X), but counts about
11 bit times per byte: {uart115 / exp115:.2f}x / {uart1m / exp1m:.2f}x the real 8N1 wire time. Round trips on simuno (row 6)
are therefore slightly pessimistic.
"""
    per_byte_ok = ctl / 8 <= TARGET
    rows = [
        row("2a. AVR receive path, cycles per wire byte (read + COBS + CRC, nothing dispatched)",
            f"<= {RX_TARGET} c/B", f"{slope:.0f} c/B", slope <= RX_TARGET, "python bench/rx_cycles.py",
            f"read via portRead() -> Stream::read() {read_per_byte:.0f} c/B + FrameReceiver::feed {feed_slope:.0f} c/B "
            f"(CRC {crc_per_byte:.0f} of it)"),
        row("2b. AVR cost of an 8-byte control frame incl. ACK (`C led=1`)", f"<= {TARGET} c/B = {TARGET * 8} cycles",
            f"{ctl:,.0f} cycles = {ctl / 8:,.0f} c/B ({ctl / F_CPU * 1e6:,.0f} us)", per_byte_ok,
            "python bench/rx_cycles.py",
            f"{other / ctl:.0%} is dispatch: find() copies one record from flash "
            f"({c[27]:,.0f} cycles)"),
        row("2c. AVR boot: begin() with Rover's 12 channels", "(part of 'device boot')",
            f"{c[2]:,.0f} cycles = {c[2] / F_CPU * 1e3:.1f} ms", None, "python bench/rx_cycles.py"),
        row("2d. AVR cost of one 28-byte descriptor chunk, downloaded in order", "(feeds row 5)",
            f"{c[35]:,.0f} cycles = {c[35] / F_CPU * 1e3:.2f} ms", None, "python bench/rx_cycles.py",
            f"out of order (offset total/2): {c[33]:,.0f} cycles"),
    ]
    save("rx_cycles", rows, details, {"cycles": c, "desc_len": desc_len, "uart_cycles_per_byte": [uart115, uart1m],
                                      "uart_expected": [exp115, exp1m]})


if __name__ == "__main__":
    run()
