"""Do the sketches of Minimal's shape (extras/bench/peers/) do what their README says? Each runs on
the simulated Uno (build/simuno) and is driven over its serial port the way its host library would:
blink_ms read, refused out of 50..5000, taken inside it and read back, the LED's toggles timed from
the pin changes simuno reports (in AVR cycles, so a busy machine does not matter), the blinking
switched off and on, the button pressed and released. Telemetrix4Arduino's firmware is driven as its
host drives it (pin 13 written, pin 2 reported).

    python bench/peers_check.py BUILD_PEERS_DIR [SIMUNO]

BUILD_PEERS_DIR is where bench/peers.sh built them (build/peers, what `bench/peers.sh --check`
passes); a sketch not built there is skipped. rosserial's host side (rosserial_python) is played by
the few frames it needs. Exits 1 when a claim does not hold.
"""

import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable

import serial
from cobs import cobs

FREQ = 16_000_000
LED = 13
PIN_LINE = re.compile(r"simuno: pin (\d+) = (\d) at cycle (\d+)")


class Uno:
    """One sketch on simuno with --watch-pins; the LED's changes collected from its stderr."""

    def __init__(self, simuno: str, elf: str, baud: int) -> None:
        self.tmp = tempfile.mkdtemp(prefix="peers-check-")
        link = os.path.join(self.tmp, "uno")
        self.proc = subprocess.Popen([simuno, elf, "--link", link, "--watch-pins"],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert self.proc.stdout is not None and self.proc.stderr is not None
        ready = self.proc.stdout.readline()
        if not ready.startswith("READY"):
            raise RuntimeError(f"simuno did not start: {ready!r}")
        self.led: list[tuple[int, int]] = []  # (value, cycle)
        self.lock = threading.Lock()
        threading.Thread(target=self._pins, daemon=True).start()
        self.port = serial.Serial(link, baud, timeout=0.05)
        time.sleep(0.3)  # past the sketch's start
        self.port.reset_input_buffer()

    def _pins(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            m = PIN_LINE.search(line)
            if m and int(m.group(1)) == LED:
                with self.lock:
                    self.led.append((int(m.group(2)), int(m.group(3))))

    def led_since(self, count: int) -> list[tuple[int, int]]:
        with self.lock:
            return self.led[count:]

    def led_count(self) -> int:
        with self.lock:
            return len(self.led)

    def button(self) -> None:
        """Press or release the button on pin 2 (simuno's SIGUSR2)."""
        self.proc.send_signal(signal.SIGUSR2)

    def close(self) -> None:
        self.port.close()
        self.proc.terminate()
        self.proc.wait(timeout=10)


failures: list[str] = []


def claim(name: str, ok: bool, detail: object = "") -> None:  # detail: shown either way
    print(f"  {'ok  ' if ok else 'FAIL'} {name} {detail}")
    if not ok:
        failures.append(name)


def blinks_every(uno: Uno, ms: int, name: str) -> None:
    """Toggles of the LED about ms apart (in AVR cycles), at least three of them."""
    start = uno.led_count()
    time.sleep(max(1.0, 5 * ms / 1000))
    changes = uno.led_since(start)
    gaps = [b[1] - a[1] for a, b in zip(changes, changes[1:])]
    ok = len(gaps) >= 3 and all(abs(g - ms * FREQ // 1000) < FREQ // 100 for g in gaps)
    claim(name, ok, f"gaps (ms): {[round(g * 1000 / FREQ, 1) for g in gaps[:6]]}")


def stays_off(uno: Uno, name: str) -> None:
    time.sleep(0.2)  # a toggle already due may still come
    start = uno.led_count()
    time.sleep(1.2)
    changes = uno.led_since(start)
    with uno.lock:
        last = uno.led[-1][0] if uno.led else 0
    claim(name, not changes and last == 0, f"changes: {len(changes)}, LED {last}")


class Link:
    """Request/answer over one framing: send() a payload, recv() the next payload (None on timeout)."""

    def __init__(self, uno: Uno) -> None:
        self.uno = uno
        self.buf = b""

    def ask(self, payload: bytes, timeout: float = 2.0) -> bytes | None:
        self.send(payload)
        return self.recv(timeout)

    def send(self, payload: bytes) -> None:
        raise NotImplementedError

    def recv(self, timeout: float = 2.0) -> bytes | None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            got = self.take()
            if got is not None:
                return got
            self.buf += self.uno.port.read(64)
        return None

    def take(self) -> bytes | None:
        raise NotImplementedError


class PacketSerialLink(Link):
    def send(self, payload: bytes) -> None:
        self.uno.port.write(cobs.encode(payload) + b"\0")

    def take(self) -> bytes | None:
        if b"\0" not in self.buf:
            return None
        frame, self.buf = self.buf.split(b"\0", 1)
        return cobs.decode(frame)

def led_then_presses(uno: Uno, led: Callable[[bool], bool], press: Callable[..., bytes | None],
                     pressed: Callable[[int], bytes]) -> None:
    """The tail every peer's Minimal-shaped sketch shares: `led` off then on (answered, the LED
    follows), then two presses reported with their count and the releases not reported."""
    claim("led off answered", led(False))
    stays_off(uno, "led off: no blinking")
    claim("led on answered", led(True))
    blinks_every(uno, 100, "blinks again")
    for n in (1, 2):
        uno.button()
        claim(f"press {n} reported", press() == pressed(n))
        uno.button()
        time.sleep(0.1)  # the sketch sees the release before the next press
    claim("release not reported", press(0.5) is None)


def crc8_table() -> list[int]:
    table = []
    for i in range(256):
        cur = i
        for _ in range(8):
            cur = ((cur << 1) ^ 0x9B) if cur & 0x80 else cur << 1
        table.append(cur & 0xFF)
    return table


class SerialTransferLink(Link):
    """Its packets: 0x7E, id, overhead byte, length, payload, CRC-8 (0x9B), 0x81. The payloads sent
    here hold no 0x7E, so nothing is stuffed (overhead byte 0xFF); received ones are unstuffed."""

    TABLE = crc8_table()

    def crc(self, data: bytes) -> int:
        c = 0
        for b in data:
            c = self.TABLE[c ^ b]
        return c

    def send_id(self, pid: int, payload: bytes) -> None:
        assert 0x7E not in payload
        self.uno.port.write(bytes([0x7E, pid, 0xFF, len(payload)]) + payload + bytes([self.crc(payload), 0x81]))

    def take(self) -> bytes | None:
        i = self.buf.find(b"\x7e")
        if i < 0 or len(self.buf) < i + 4 or len(self.buf) < i + 4 + self.buf[i + 3] + 2:
            return None
        pid, over, n = self.buf[i + 1], self.buf[i + 2], self.buf[i + 3]
        data = bytearray(self.buf[i + 4:i + 4 + n])
        crc, end = self.buf[i + 4 + n], self.buf[i + 5 + n]
        self.buf = self.buf[i + 6 + n:]
        if crc != self.crc(data) or end != 0x81:
            return b"bad packet"
        while over != 0xFF and over < n:  # the library's unstuffing: each 0x7E holds the gap to the next
            step = data[over]
            data[over] = 0x7E
            over = 0xFF if step == 0 else over + step
        return bytes([pid]) + bytes(data)


class FirmataLink(Link):
    """Firmata's messages: sysex 0xF0 ... 0xF7, digital port reports 0x90|port lsb msb; the version
    report (0xF9 major minor) is skipped."""

    def send(self, payload: bytes) -> None:
        self.uno.port.write(payload)

    def take(self) -> bytes | None:
        while self.buf:
            b = self.buf[0]
            if b == 0xF0:
                end = self.buf.find(b"\xf7")
                if end < 0:
                    return None
                msg, self.buf = self.buf[:end + 1], self.buf[end + 1:]
                if msg[1] == 0x79:  # the firmware name
                    continue
                return msg
            if b & 0xF0 == 0x90 or b == 0xF9:
                if len(self.buf) < 3:
                    return None
                msg, self.buf = self.buf[:3], self.buf[3:]
                if b == 0xF9:
                    continue
                return msg
            self.buf = self.buf[1:]
        return None


class RosLink(Link):
    """rosserial's protocol 2: 0xFF 0xFE, length (LE u16) and its checksum, topic id (LE u16), the
    message, a checksum. Time requests (topic 10) from the board are answered as they come, as
    rosserial_python does, or the board takes the link for lost."""

    TIME = 10

    @staticmethod
    def frame(topic: int, data: bytes) -> bytes:
        n = len(data).to_bytes(2, "little")
        t = topic.to_bytes(2, "little")
        return b"\xff\xfe" + n + bytes([255 - sum(n) % 256]) + t + data + bytes([255 - (sum(t) + sum(data)) % 256])

    def send_to(self, topic: int, data: bytes) -> None:
        self.uno.port.write(self.frame(topic, data))

    def take(self) -> bytes | None:
        while True:
            i = self.buf.find(b"\xff\xfe")
            if i < 0 or len(self.buf) < i + 7:
                return None
            n = int.from_bytes(self.buf[i + 2:i + 4], "little")
            if len(self.buf) < i + 8 + n:
                return None
            msg, self.buf = self.buf[i:i + 8 + n], self.buf[i + 8 + n:]
            if msg != self.frame(int.from_bytes(msg[5:7], "little"), msg[7:-1]):
                return b"bad frame"
            if int.from_bytes(msg[5:7], "little") == self.TIME:
                self.send_to(self.TIME, bytes(8))  # time 0 s 0 ns: any answer keeps the link
                continue
            return msg[5:-1]  # topic id (2 bytes) and message

    def next_on(self, topic: int, timeout: float = 3.0) -> bytes | None:
        """The next message on topic, others skipped."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            got = self.recv(deadline - time.monotonic())
            if got is not None and int.from_bytes(got[:2], "little") == topic:
                return got[2:]
        return None


def topic_info(data: bytes) -> tuple[int, str, str]:
    """rosserial_msgs/TopicInfo: u16 id, then strings (u32 length, bytes): name, type, md5."""
    tid = int.from_bytes(data[:2], "little")
    out, at = [], 2
    for _ in range(2):
        n = int.from_bytes(data[at:at + 4], "little")
        out.append(data[at + 4:at + 4 + n].decode())
        at += 4 + n
    return tid, out[0], out[1]


def check_packetserial(uno: Uno) -> None:
    link = PacketSerialLink(uno)
    claim("read blink_ms", link.ask(b"r") == b"v" + (500).to_bytes(2, "little"))
    blinks_every(uno, 500, "blinks every 500 ms")
    claim("write 49 refused", link.ask(b"w" + (49).to_bytes(2, "little")) == b"n")
    claim("write 5001 refused", link.ask(b"w" + (5001).to_bytes(2, "little")) == b"n")
    claim("write 100 taken", link.ask(b"w" + (100).to_bytes(2, "little")) == b"a")
    claim("read back 100", link.ask(b"r") == b"v" + (100).to_bytes(2, "little"))
    blinks_every(uno, 100, "blinks every 100 ms")
    claim("unknown packet refused", link.ask(b"x") == b"n")
    led_then_presses(uno, lambda on: link.ask(b"l" + bytes([on])) == b"a", link.recv, lambda n: b"b" + bytes([n]))


def check_serialtransfer(uno: Uno) -> None:
    link = SerialTransferLink(uno)

    def ask(pid: int, payload: bytes) -> bytes | None:
        link.send_id(pid, payload)
        return link.recv()

    le = lambda v: v.to_bytes(2, "little")  # noqa: E731
    claim("read blink_ms", ask(0, b"\0") == b"\0" + le(500))
    blinks_every(uno, 500, "blinks every 500 ms")
    claim("write 49 refused", ask(1, le(49)) == b"\1\0" + le(500))
    claim("write 5001 refused", ask(1, le(5001)) == b"\1\0" + le(500))
    claim("write 100 taken", ask(1, le(100)) == b"\1\1" + le(100))
    claim("read back 100", ask(0, b"\0") == b"\0" + le(100))
    blinks_every(uno, 100, "blinks every 100 ms")
    link.uno.port.write(bytes([0x7E, 1, 0xFF, 2, 100, 0, 0x00, 0x81]))  # a wrong CRC
    claim("damaged packet not answered", link.recv(0.5) is None)
    led_then_presses(uno, lambda on: ask(2, bytes([on])) == b"\2\1", link.recv, lambda n: b"\3" + bytes([n]))


def check_firmata(uno: Uno) -> None:
    link = FirmataLink(uno)

    def sysex(*data: int) -> bytes:  # each byte as two 7-bit bytes, as the library sends them
        return bytes([0xF0, 0x01, *(b for d in data for b in (d & 0x7F, d >> 7)), 0xF7])

    def low_high(v: int) -> tuple[int, int]:
        return v & 0xFF, v >> 8

    claim("read blink_ms", link.ask(sysex()) == sysex(1, *low_high(500)))
    blinks_every(uno, 500, "blinks every 500 ms")
    claim("write 49 refused", link.ask(sysex(*low_high(49))) == sysex(0, *low_high(500)))
    claim("write 5001 refused", link.ask(sysex(*low_high(5001))) == sysex(0, *low_high(500)))
    claim("write 100 taken", link.ask(sysex(*low_high(100))) == sysex(1, *low_high(100)))
    claim("read back 100", link.ask(sysex()) == sysex(1, *low_high(100)))
    blinks_every(uno, 100, "blinks every 100 ms")
    link.send(bytes([0x91, 0x00, 0x00]))  # pins 8..15 low: pin 13 off
    stays_off(uno, "led off: no blinking")
    link.send(bytes([0x91, 1 << 5, 0x00]))  # pin 13 high
    blinks_every(uno, 100, "blinks again")
    uno.button()
    claim("press reported (pin 2 low)", link.recv() == bytes([0x90, 0, 0]))
    uno.button()
    claim("release reported (pin 2 high)", link.recv() == bytes([0x90, 1 << 2, 0]))


def check_rosserial(uno: Uno) -> None:
    link = RosLink(uno)
    link.send_to(0, b"")  # what rosserial_python sends first: the board describes its topics
    topics: dict[tuple[int, str], tuple[int, str]] = {}
    deadline = time.monotonic() + 3
    while time.monotonic() < deadline and len(topics) < 5:
        got = link.recv(0.5)
        if got is not None and int.from_bytes(got[:2], "little") in (0, 1, 2, 3):
            tid, name, kind = topic_info(got[2:])
            topics[(int.from_bytes(got[:2], "little"), name)] = (tid, kind)
    want = {(0, "blink_ms"): "std_msgs/UInt16", (0, "button"): "std_msgs/UInt8",
            (1, "blink_ms/set"): "std_msgs/UInt16", (2, "led"): "std_srvs/SetBool",
            (3, "led"): "std_srvs/SetBool"}
    claim("topics described", {k: v[1] for k, v in topics.items()} == want, sorted(topics))
    if not all(k in topics for k in want):
        return
    value, button, setter, led, led_answer = (topics[k][0] for k in (
        (0, "blink_ms"), (0, "button"), (1, "blink_ms/set"), (3, "led"), (2, "led")))
    le = lambda v: v.to_bytes(2, "little")  # noqa: E731
    claim("read blink_ms (published each second)", link.next_on(value) == le(500))
    blinks_every(uno, 500, "blinks every 500 ms")
    for ms, now, name in ((49, 500, "write 49 refused"), (5001, 500, "write 5001 refused"), (100, 100, "write 100 taken")):
        link.send_to(setter, le(ms))
        # The answer is blink_ms published right after the write; the once-a-second one may be on
        # its way already, so the last of those that come within 0.3 s is the answer.
        got = []
        while (m := link.next_on(value, 0.3)) is not None:
            got.append(m)
        claim(name, got[-1:] == [le(now)], got)
    blinks_every(uno, 100, "blinks every 100 ms")

    def switch(on: bool) -> bool:
        link.send_to(led, bytes([on]))
        return link.next_on(led_answer) == b"\1" + bytes(4)  # success, message ""
    led_then_presses(uno, switch, lambda t=3.0: link.next_on(button, t), lambda n: bytes([n]))


def check_telemetrix(uno: Uno) -> None:
    """Its firmware as Minimal's shape: the host switches pin 13 (so it times the blinking) and
    sets pin 2 as an input the firmware reports; messages are [length, command or report, ...]."""
    time.sleep(2.5)  # the firmware blinks pin 13 four times while it starts
    uno.port.reset_input_buffer()
    link = PacketlessLink(uno)
    link.send(bytes([3, 1, 13, 1]))  # set_pin_mode 13 OUTPUT
    link.send(bytes([4, 1, 2, 2, 1]))  # set_pin_mode 2 INPUT_PULLUP, reporting on
    claim("pin 2 reported when set (high)", link.recv() == bytes([3, 2, 2, 1]))
    start = uno.led_count()
    for i in range(6):
        link.send(bytes([3, 2, 13, (i + 1) % 2]))  # digital_write 13: the host blinks the LED
        time.sleep(0.1)
    time.sleep(0.2)
    claim("the host's writes switch pin 13", [v for v, _ in uno.led_since(start)] == [1, 0] * 3)
    uno.button()
    claim("press reported (pin 2 low)", link.recv() == bytes([3, 2, 2, 0]))
    uno.button()
    claim("release reported (pin 2 high)", link.recv() == bytes([3, 2, 2, 1]))


class PacketlessLink(Link):
    """Telemetrix's messages: a length byte, then that many bytes."""

    def send(self, payload: bytes) -> None:
        self.uno.port.write(payload)

    def take(self) -> bytes | None:
        if not self.buf or len(self.buf) < 1 + self.buf[0]:
            return None
        msg, self.buf = self.buf[:1 + self.buf[0]], self.buf[1 + self.buf[0]:]
        return msg


CHECKS = (("PacketSerialMinimal", 115200, check_packetserial),
          ("SerialTransferMinimal", 115200, check_serialtransfer),
          ("Telemetrix4Arduino", 115200, check_telemetrix),
          ("RosserialMinimal", 57600, check_rosserial),
          ("FirmataMinimal", 57600, check_firmata))


def main() -> None:
    peers = sys.argv[1]
    simuno = sys.argv[2] if len(sys.argv) > 2 else "build/simuno/simuno"
    for name, baud, check in CHECKS:
        elf = os.path.join(peers, name, f"{name}.ino.elf")
        if not os.path.exists(elf):
            print(f"{name}: not built, skipped")
            continue
        print(name)
        uno = Uno(simuno, elf, baud)
        try:
            check(uno)
        finally:
            uno.close()
    if failures:
        print(f"peers_check: {len(failures)} claims do not hold: {failures}")
        sys.exit(1)


if __name__ == "__main__":
    main()
