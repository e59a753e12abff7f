// The Arduino-only part of the library: where a per-boot nonce comes from.
#include "Hubwire.h"

namespace hubwire {

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
  bootCounter = bootCounter * 1664525UL + 1013904223UL;  // an LCG step per boot
  uint32_t n = bootCounter ^ (micros() * 2654435761UL);
  return n ? n : 1;
}

}  // namespace hubwire
