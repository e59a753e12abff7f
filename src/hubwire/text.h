// A string that lives either in RAM or, on AVR, in flash; read one character at a time.
#ifndef HUBWIRE_TEXT_H
#define HUBWIRE_TEXT_H

#include <stdint.h>

#if defined(__AVR__)
#include <avr/pgmspace.h>
#endif

namespace hubwire {

struct Text {
  const char* ptr;
  bool flash;

  constexpr Text() : ptr(nullptr), flash(false) {}
  constexpr Text(const char* s) : ptr(s), flash(false) {}  // NOLINT: implicit on purpose
  constexpr Text(const char* s, bool inFlash) : ptr(s), flash(inFlash) {}

  char at(uint16_t i) const {
#if defined(__AVR__)
    if (flash) return (char)pgm_read_byte(ptr + i);
#endif
    return ptr[i];
  }
};

inline Text flashText(const char* s) { return Text(s, true); }

// Puts a constant table in flash on AVR (elsewhere constants are not in RAM anyway); read it
// through a flash Text.
#if defined(__AVR__)
#define HUBWIRE_FLASH PROGMEM
#else
#define HUBWIRE_FLASH
#endif

}  // namespace hubwire

#endif
