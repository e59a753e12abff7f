// libFuzzer harness: arbitrary bytes into the C++ FrameReceiver (src/hubwire/wire/frame.*).
//
// Input: byte 0 picks the receiver's accepted payload (0..255, so the buffer holds 5..260 raw bytes;
// allocated to the exact size so AddressSanitizer sees any overrun), the rest is the line.
// Checks, beyond the sanitizers:
//   - a completed frame fits the buffer (len <= capacity - 5) and its payload lies inside it;
//   - re-encoding it (encodeFrame) and feeding that to a fresh receiver gives the same frame back;
//   - the drop counters only ever grow by one per delimiter, and every delimiter that ends a
//     non-empty frame either completes a frame or bumps exactly one counter.
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hubwire/wire/frame.h"

using namespace hubwire;

// The core links FrameWriter, which writes through the port seam: a binding that discards.
int hubwire::portRead(Port&) { return -1; }
void hubwire::portWrite(Port&, const uint8_t*, size_t) {}
size_t hubwire::portWritable(Port&) { return 0; }
uint32_t hubwire::portMillis(Port&) { return 0; }
uint32_t hubwire::portMicros(Port&) { return 0; }
uint8_t hubwire::portBoardId(Port&, uint8_t*) { return 0; }

#define CHECK(c)                                                         \
  do {                                                                   \
    if (!(c)) {                                                          \
      fprintf(stderr, "fuzz_frame: check failed: %s (line %d)\n", #c, __LINE__); \
      abort();                                                           \
    }                                                                    \
  } while (0)

static uint32_t total(const LinkCounters& c) { return (uint32_t)c.crc + c.overflow + c.dropped; }

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  uint16_t maxPayload = data[0];
  uint16_t cap = (uint16_t)HUBWIRE_RAW_FRAME_SIZE(maxPayload);
  uint8_t* buf = new uint8_t[cap];
  FrameReceiver rx(buf, cap);
  bool started = false;
  for (size_t i = 1; i < size; ++i) {
    uint8_t b = data[i];
    uint32_t before = total(rx.counters);
    bool got = rx.feed(b);
    uint32_t after = total(rx.counters);
    if (b != 0) {
      CHECK(!got);
      CHECK(after == before);
      started = true;
      continue;
    }
    if (!started) {
      CHECK(!got && after == before);  // lone delimiter: ignored, not counted
      continue;
    }
    started = false;
    CHECK(got ? after == before : after == before + 1);
    if (!got) continue;
    const Frame& f = rx.frame();
    CHECK(f.len + kFrameOverhead <= cap);
    CHECK(f.payload == buf + kFrameHeader);
    uint8_t wire[FrameWriter::wireSize(255) + 8];
    size_t n = encodeFrame(f.type, f.seq, f.id, f.payload, f.len, wire);
    CHECK(n <= FrameWriter::wireSize(f.len));
    CHECK(wire[n - 1] == 0);
    for (size_t k = 0; k + 1 < n; ++k) CHECK(wire[k] != 0);
    uint8_t buf2[HUBWIRE_RAW_FRAME_SIZE(255)];
    FrameReceiver rx2(buf2, sizeof(buf2));
    bool again = false;
    for (size_t k = 0; k < n; ++k) again = rx2.feed(wire[k]);
    CHECK(again);
    const Frame& g = rx2.frame();
    CHECK(g.type == f.type && g.seq == f.seq && g.id == f.id && g.len == f.len);
    CHECK(memcmp(g.payload, f.payload, f.len) == 0);
  }
  delete[] buf;
  return 0;
}
