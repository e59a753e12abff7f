// Large1K: a 1 KB struct (HUBWIRE_MAX_VALUE, the default cap) on a 32-bit board, for the hub's
// end-to-end tests in the emulator (build/emulator/hubwire-large-emulator): written and read
// whole through fragments, streamed as fragmented samples, with a List beside it.
#include <Hubwire.h>

Hubwire hub(Serial);

struct Big {
  uint32_t words[200];  // 800 bytes
  float f[56];          // 224 bytes
} big;

hubwire::List<uint32_t, 64> tail;  // 257 bytes on the wire when full: large too
uint32_t bigWrites, tailWrites;
uint32_t checksum;  // of big as last written: the hub compares it with what it sent

void bigChanged() {
  ++bigWrites;
  uint32_t h = 2166136261UL;
  const uint8_t* p = (const uint8_t*)&big;
  for (size_t i = 0; i < sizeof(big); ++i) h = (h ^ p[i]) * 16777619UL;
  checksum = h;
}
void tailChanged() { ++tailWrites; }

uint32_t total(const hubwire::List<uint32_t, 64>& v) {
  uint32_t s = 0;
  for (uint8_t i = 0; i < v.size(); ++i) s += v[i];
  return s;
}

HUBWIRE_CHANNELS(channels, "large1k",
  expose("big", big, "words:u32[200],f:f32[56]").writable().streamable().onChange(bigChanged),
  expose("tail", tail).writable().streamable().onChange(tailChanged),
  action("total", total),
  expose("big_writes", bigWrites),
  expose("tail_writes", tailWrites),
  expose("checksum", checksum));

void setup() {
  for (uint16_t i = 0; i < 200; ++i) big.words[i] = i * 1000003UL;
  for (uint8_t i = 0; i < 56; ++i) big.f[i] = i * 0.25f;
  bigChanged();
  bigWrites = 0;
  Serial.begin(115200);
  hub.begin(channels);
}

void loop() {
  hub.update();
}
