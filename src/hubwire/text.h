// A string that lives either in RAM or, on AVR, in flash (from F()); read one character at a time.
#ifndef HUBWIRE_TEXT_H
#define HUBWIRE_TEXT_H

#include <stdint.h>

#if defined(__AVR__)
#include <avr/pgmspace.h>
#endif

// Arduino's F() yields this type; declaring it here keeps the core free of Arduino.h.
class __FlashStringHelper;

namespace hubwire {

struct Text {
  const char* ptr;
  bool flash;

  constexpr Text() : ptr(nullptr), flash(false) {}
  constexpr Text(const char* s) : ptr(s), flash(false) {}  // NOLINT: implicit on purpose
  Text(const __FlashStringHelper* s) : ptr(reinterpret_cast<const char*>(s)), flash(true) {}  // NOLINT
  constexpr Text(const char* s, bool inFlash) : ptr(s), flash(inFlash) {}

  char at(uint16_t i) const {
#if defined(__AVR__)
    if (flash) return (char)pgm_read_byte(ptr + i);
#endif
    return ptr[i];
  }
  bool empty() const { return ptr == nullptr || at(0) == 0; }
  uint16_t length() const {
    uint16_t n = 0;
    if (ptr)
      while (at(n)) ++n;
    return n;
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

// A string literal kept in flash on AVR (where literals otherwise cost RAM), as a Text.
#if defined(__AVR__)
#define HUBWIRE_TEXT(s) ::hubwire::flashText(PSTR(s))
#else
#define HUBWIRE_TEXT(s) ::hubwire::Text(s)
#endif

}  // namespace hubwire

#endif
