// RxCycles: AVR cycle cost of Hubwire's receive path, measured in simavr (bench/rx_cycles.py).
//
// Frames are encoded here at start-up (hubwire::encodeFrame) and fed to hub.update() through a
// RAM-backed Stream, so the UART is not in the measurement; replies go to a Stream that only
// counts bytes. Every measured region is bracketed by two writes to GPIOR0:
//   GPIOR0 = k (start of region k)  ...  GPIOR0 = k | 0x80 (end of region k)
// and `simuno --fast --cycles-log FILE` logs "value cycle" for each write (avr->cycle, exact).
// Timer0's interrupt is off while measuring: millis() stands still, no ISR lands in a region.
// The channels are examples/Rover's twelve, from its channels.h: the same ids, records and descriptor.
// At the end the sketch times Serial at two baud rates (does simavr model UART timing?) and stops
// the MCU (simuno exits 0). Region ids: see bench/rx_cycles.py (REGIONS).
#include <Hubwire.h>
#include <avr/sleep.h>

#include "hubwire/wire/crc16.h"

// ---- streams ----------------------------------------------------------------------------------
class FeedStream : public Stream {
 public:
  const uint8_t* p = nullptr;
  uint16_t n = 0;
  uint16_t written = 0;
  void load(const uint8_t* data, uint16_t len) {
    p = data;
    n = len;
  }
  int available() override { return n; }
  int read() override {
    if (!n) return -1;
    --n;
    return *p++;
  }
  int peek() override { return n ? *p : -1; }
  size_t write(uint8_t) override {
    ++written;
    return 1;
  }
  size_t write(const uint8_t*, size_t len) override {
    written += len;
    return len;
  }
  int availableForWrite() override { return 63; }
  void flush() override {}
};

FeedStream feed;
Hubwire hub(feed);

// ---- examples/Rover's channels: its own header (the build passes -I examples/Rover) ------------
#include "channels.h"

void countWrite() { ++applied; }
void ledChanged() { ++applied; }
bool beep(uint16_t ms) { return ms <= 2000; }
uint8_t selftest(uint8_t count) { return count; }

// ---- helpers ------------------------------------------------------------------------------------
#define BARRIER() asm volatile("" ::: "memory")
static inline void markStart(uint8_t k) {
  BARRIER();
  GPIOR0 = k;
  BARRIER();
}
static inline void markEnd(uint8_t k) {
  BARRIER();
  GPIOR0 = (uint8_t)(k | 0x80);
  BARRIER();
}

uint8_t wire[80];
uint8_t wireLen;
uint8_t hubSeq = 10;

void encode(uint8_t type, uint8_t seq, uint8_t id, const uint8_t* payload, uint8_t len) {
  wireLen = (uint8_t)hubwire::encodeFrame(type, seq, id, payload, len, wire);
}

// Feeds the encoded frame to hub.update() as region k (run `reps` times, each with a new seq when
// `newSeq`), so the log shows the cost is the same every time.
void measureUpdate(uint8_t k, uint8_t type, uint8_t id, const uint8_t* payload, uint8_t len, bool newSeq,
                   uint8_t reps = 3) {
  for (uint8_t r = 0; r < reps; ++r) {
    encode(type, newSeq ? ++hubSeq : 0, id, payload, len);
    feed.load(wire, wireLen);
    markStart(k);
    hub.update();
    markEnd(k);
  }
}

void stop() {
  GPIOR0 = 0xFF;  // end of log
  cli();
  set_sleep_mode(SLEEP_MODE_PWR_DOWN);
  sleep_enable();
  sleep_cpu();
}

void setup() {
  TIMSK0 = 0;  // no timer0 interrupt: millis() stands still, no ISR inside a region

  markStart(1);  // 1: calibration (empty region)
  markEnd(1);

  // 2: begin(): the 12 declarations were checked and the descriptor hashed when this sketch
  // compiled; begin() gives the event its id (it copies nothing and sends nothing)
  markStart(2);
  bool ok = hub.begin(channels);
  markEnd(2);
  if (!ok) stop();

  // Link: a hub hello (version 1, flags 0, nonce, accepts 255, heartbeat 250 ms).
  static const uint8_t hello[16] = {1, 0, 0x78, 0x56, 0x34, 0x12, 255, 0, 250, 0, 0, 0, 0, 0, 0, 0};
  measureUpdate(3, '*', 0, hello, 16, false, 1);  // 3: hub hello -> link up, hello reply
  markStart(4);  // 4: first update after link-up (sends the first heartbeat)
  hub.update();
  markEnd(4);
  for (uint8_t r = 0; r < 3; ++r) {  // 5: idle update(), nothing received
    feed.load(wire, 0);
    markStart(5);
    hub.update();
    markEnd(5);
  }

  static const uint8_t hb[10] = {1, 0, 250, 0, 0, 0, 0, 0, 0, 0};
  measureUpdate(6, 'H', 0, hb, 10, false);        // 6: hub heartbeat (no answer, no channel lookup)
  measureUpdate(7, 0x07, 9, nullptr, 0, false);   // 7: stray ACK (empty payload, no event in flight)
  static const uint8_t on[1] = {1};
  measureUpdate(8, 'C', 6, on, 1, true);           // 8: C led=1 (bool, ch 6): 8 wire bytes, ACK
  static const uint8_t half[4] = {0, 0, 0, 0x3F};  // 0.5f
  measureUpdate(9, 'C', 1, half, 4, true);         // 9: C left=0.5 (f32 + range, ch 1), ACK
  measureUpdate(10, 'C', 2, half, 4, true);        // 10: C right=0.5 (f32 + range, ch 2), ACK
  measureUpdate(11, 'R', 1, nullptr, 0, true);     // 11: R left (ch 1) -> r f32
  measureUpdate(12, 'R', 12, nullptr, 0, true);    // 12: R applied (ch 12) -> r u32
  measureUpdate(13, 'R', 3, nullptr, 0, true);     // 13: R imu (ch 3, struct) -> r 18 B
  static const uint8_t nm[9] = {8, 'b', 'e', 'n', 'c', 'h', 'b', 'o', 't'};
  measureUpdate(14, 'C', 7, nm, 9, true);          // 14: C name="benchbot" (str, ch 7), ACK
  static const uint8_t ms[2] = {100, 0};
  measureUpdate(15, 'C', 9, ms, 2, true);          // 15: C beep(100) (action, ch 9) -> r bool
  static const uint8_t sev[1] = {1};
  measureUpdate(16, 'C', 10, sev, 1, true);        // 16: C selftest(1) (action, ch 10) -> r u8
  static const uint8_t pl8[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  measureUpdate(17, 'H', 0, pl8, 8, false);        // 17: 'H' with 8-byte payload (short heartbeat)
  static uint8_t big[32];
  for (uint8_t i = 0; i < 32; ++i) big[i] = (uint8_t)(i + 1);
  measureUpdate(18, 'H', 0, big, 32, false);       // 18: 'H' with a 32-byte payload (rx path slope)
  measureUpdate(19, 'R', 5, nullptr, 0, true);     // 19: R battery (ch 5, u16) -> r u16
  measureUpdate(28, 'R', 11, nullptr, 0, true);    // 28: R failsafes (ch 11, u16) -> r u16
  // Descriptor chunks (28 bytes each), copied from the JSON in flash: asked out of order (32-34) or
  // in order (35), a chunk should cost the same wherever it starts.
  uint16_t total = hub.descriptorLength();
  uint8_t jr[3] = {0, 0, 28};
  measureUpdate(32, 'J', 0, jr, 3, true, 1);       // 32: J offset 0
  uint16_t mid = (uint16_t)(total / 2);
  jr[0] = (uint8_t)mid;
  jr[1] = (uint8_t)(mid >> 8);
  measureUpdate(33, 'J', 0, jr, 3, true, 1);       // 33: J offset total/2
  uint16_t last = (uint16_t)(total > 28 ? total - 28 : 0);
  jr[0] = (uint8_t)last;
  jr[1] = (uint8_t)(last >> 8);
  measureUpdate(34, 'J', 0, jr, 3, true, 1);       // 34: J offset total-28 (last full chunk)
  // 35: a whole download in order, as the hub asks for it: each chunk resumes where the last ended.
  for (uint16_t off = 0; off < total; off = (uint16_t)(off + 28)) {
    jr[0] = (uint8_t)off;
    jr[1] = (uint8_t)(off >> 8);
    measureUpdate(35, 'J', 0, jr, 3, true, 1);
  }
  GPIOR0 = 0xFE;  // data, not a mark: the descriptor length, low byte then high byte
  GPIOR0 = (uint8_t)total;
  GPIOR0 = (uint8_t)(total >> 8);

  // ---- parts, measured alone on the same bytes as region 8 (C led=1) ----
  encode('C', 77, 6, on, 1);
  {
    static uint8_t rxbuf[HUBWIRE_RAW_FRAME_SIZE(HUBWIRE_MAX_PAYLOAD)];
    hubwire::FrameReceiver rx(rxbuf, sizeof(rxbuf));
    bool got = false;
    markStart(20);  // 20: FrameReceiver::feed() over the 8 wire bytes (COBS + CRC + checks)
    for (uint8_t i = 0; i < wireLen; ++i) got |= rx.feed(wire[i]);
    markEnd(20);
    if (!got) stop();
    static volatile uint16_t sink;
    const uint8_t raw[4] = {'C', 77, 6, 1};
    markStart(21);  // 21: crc16() over the 4 header+payload bytes
    sink = hubwire::crc16(raw, 4);
    markEnd(21);
    encode('H', 0, 0, big, 32);
    markStart(22);  // 22: FrameReceiver::feed() over a 39-byte frame (32-byte payload)
    for (uint8_t i = 0; i < wireLen; ++i) got |= rx.feed(wire[i]);
    markEnd(22);
    static uint8_t raw32[35];
    markStart(23);  // 23: crc16() over 35 bytes
    sink = hubwire::crc16(raw32, 35);
    markEnd(23);
    (void)sink;
  }
  {
    hubwire::Port ports(feed);  // the same read hub.update() does: portRead() -> Stream::read()
    encode('C', 78, 6, on, 1);
    feed.load(wire, wireLen);
    static volatile int last;
    markStart(24);  // 24: reading the 8 bytes through portRead() -> Stream::read()
    for (uint8_t i = 0; i < 8; ++i) last = hubwire::portRead(ports);
    markEnd(24);
    markStart(25);  // 25: reading 8 bytes from the stub stream alone
    for (uint8_t i = 0; i < 8; ++i) last = feed.read();
    markEnd(25);
    (void)last;
  }
  {
    static uint8_t txbuf[HUBWIRE_SEND_FRAME_SIZE(HUBWIRE_MAX_PAYLOAD)];
    hubwire::FrameWriter tx(txbuf);
    hubwire::Port sink(feed);  // the device's own write path, minus the UART
    markStart(26);  // 26: FrameWriter::send() of an empty ACK (CRC + COBS + writes)
    tx.send(sink, 0x07, 12, 6, 0);
    markEnd(26);
    markStart(29);  // 29: FrameWriter::send() of a 4-byte 'r'
    tx.send(sink, 'r', 12, 1, 4);
    markEnd(29);
  }
  {
    // 27: copying one channel's record from flash: what find(id) costs, the same for every id
    // (the records are an array in flash, nothing is replayed)
    static hubwire::ChannelInfo ch;
    markStart(27);
    memcpy_P(&ch, &channels.channels[11], sizeof(ch));
    markEnd(27);
  }

  // ---- does simavr model the UART's baud rate? 100 bytes out, then wait for TX complete ----
  static const uint32_t bauds[2] = {115200UL, 1000000UL};
  for (uint8_t b = 0; b < 2; ++b) {
    Serial.begin(bauds[b]);
    Serial.write((uint8_t)0);  // settle: the first byte goes straight to UDR
    Serial.flush();
    UCSR0A = (uint8_t)((UCSR0A & (_BV(U2X0) | _BV(MPCM0))) | _BV(TXC0));  // clear TX complete
    markStart((uint8_t)(30 + b));  // 30: 115200, 31: 1000000
    for (uint8_t i = 0; i < 100; ++i) {
      while (!(UCSR0A & _BV(UDRE0))) {
      }
      UDR0 = 'U';
    }
    while (!(UCSR0A & _BV(TXC0))) {
    }
    markEnd((uint8_t)(30 + b));
    Serial.end();
  }
  stop();
}

void loop() {}
