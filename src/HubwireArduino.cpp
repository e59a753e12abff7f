// The Arduino-only part of the library: the core's seam bound to a Stream and millis(), and where
// a per-boot nonce comes from.
#include "Hubwire.h"

// ESP-IDF 5 (arduino-esp32 3.x) no longer declares esp_random() through esp_system.h; the header
// of its own exists from IDF 4.1 on, and older cores get it through Arduino.h.
#if defined(ESP32) && defined(__has_include)
#if __has_include(<esp_random.h>)
#include <esp_random.h>
#endif
#endif

namespace hubwire {

int portRead(Port& p) { return p.stream.read(); }
void portWrite(Port& p, const uint8_t* data, size_t len) { p.stream.write(data, len); }
size_t portWritable(Port& p) {
  int n = p.stream.availableForWrite();
  // A transmit buffer as empty as it has ever been will not get emptier: a frame larger than the
  // whole buffer goes now (write() waits for the rest) instead of never. The same rule lets frames
  // go on cores that never implement availableForWrite() (always 0), where room is unknown.
  if (n < p.mostRoom) return (size_t)n;
  p.mostRoom = (uint8_t)(n > 255 ? 255 : n);
  return 0xFFFF;
}
uint32_t portMillis(Port&) { return ::millis(); }
uint32_t portMicros(Port&) { return ::micros(); }

#if defined(__AVR__)
// Survives a reset (not a power cycle, where RAM starts random anyway), so each boot differs.
static uint32_t bootCounter __attribute__((section(".noinit")));
#else
static uint32_t bootCounter;
#endif

#if defined(HUBWIRE_NONCE_SOURCE)
uint32_t HUBWIRE_NONCE_SOURCE();  // a build may supply its own entropy (the Linux emulator does)
#endif

uint32_t bootNonce() {
#if defined(HUBWIRE_NONCE_SOURCE)
  bootCounter ^= HUBWIRE_NONCE_SOURCE();
#elif defined(ESP32)
  bootCounter ^= esp_random();
#endif
  // Differs from the last boot; Session mixes in the moment the hub is first heard and its nonce.
  return ++bootCounter;
}

}  // namespace hubwire
