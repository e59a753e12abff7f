// Constants in flash: a string that lives either in RAM or, on AVR, in flash, read one character
// at a time; the sections that keep constants in flash (HUBWIRE_FLASH, HUBWIRE_FOLDED); reading
// them back (flashCopy, flashRead).
#ifndef HUBWIRE_TEXT_H
#define HUBWIRE_TEXT_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "config.h"

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

// Puts a constant table in flash where constants would otherwise be copied to RAM: on AVR (read
// through a flash Text or memcpy_P) and on Teensy 4 (i.MX RT1062), whose linker script puts .rodata
// in RAM and whose PROGMEM is this section of the memory-mapped flash (read like RAM). Elsewhere
// (ARM Cortex-M with flash, ESP32, RP2040, a PC) constants stay in flash or are memory anyway.
#if defined(__AVR__)
#define HUBWIRE_FLASH PROGMEM
#elif defined(__IMXRT1062__)
#define HUBWIRE_FLASH __attribute__((section(".progmem")))
#else
#define HUBWIRE_FLASH
#endif
// The same for a constant read like any other (no pgm_read on AVR, where it stays as it is).
#if defined(__IMXRT1062__)
#define HUBWIRE_RODATA HUBWIRE_FLASH
#else
#define HUBWIRE_RODATA
#endif
// A constant that link-time optimisation folds into the code reading it (a sketch's features,
// table and hooks, and the library's weak defaults for them). On AVR each has a section of its
// own, which the linker drops once every read was folded: LTO still emits a constant that code in
// another partition read, and in a section shared with one still read it would stay in RAM. User
// alignment keeps GCC's identical-constant folding from merging two equal ones (two null hooks, a
// table and its flash copy): merged, their reads were no longer folded.
#if defined(__AVR__)
#define HUBWIRE_FOLDED(name) __attribute__((section(".rodata.hubwire." name), aligned(2)))
#else
#define HUBWIRE_FOLDED(name) HUBWIRE_RODATA __attribute__((aligned(2)))
#endif

// Copies n bytes of a table's flash (HUBWIRE_FLASH) into RAM.
inline void flashCopy(void* to, const void* from, size_t n) {
#if defined(__AVR__)
  memcpy_P(to, from, n);
#else
  memcpy(to, from, n);
#endif
}

// One field of a table's flash (a byte, a word or a double word): on AVR read inline with
// pgm_read_*, where memcpy_P is a call and a frame on the stack.
#if defined(__AVR__)
template <size_t N>
struct FlashBits;
template <>
struct FlashBits<1> {
  static uint8_t read(const void* at) { return pgm_read_byte(at); }
};
template <>
struct FlashBits<2> {
  static uint16_t read(const void* at) { return pgm_read_word(at); }
};
template <>
struct FlashBits<4> {
  static uint32_t read(const void* at) { return pgm_read_dword(at); }
};
#endif
template <typename T>
HUBWIRE_ALWAYS_INLINE T flashRead(const T* at) {
#if defined(__AVR__)
  auto bits = FlashBits<sizeof(T)>::read(at);
  T v;
  memcpy(&v, &bits, sizeof(v));
  return v;
#else
  return *at;
#endif
}

}  // namespace hubwire

#endif
