// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection): check value 0x29B1 for "123456789".
#ifndef HUBWIRE_WIRE_CRC16_H
#define HUBWIRE_WIRE_CRC16_H

#include <stddef.h>
#include <stdint.h>

namespace hubwire {

const uint16_t kCrcInit = 0xFFFF;

// One byte into the CRC, table-free. With x = (crc >> 8) ^ byte, x ^= x >> 4, the new CRC is
// (crc << 8) ^ (x << 12) ^ (x << 5) ^ x. On AVR the same in 16 instructions, a third fewer than
// avr-libc's _crc_xmodem_update(): the high byte takes (x << 4) from one swap and x >> 3 from
// three shifts, the low byte (x << 5) from that swap shifted once.
inline uint16_t crc16Update(uint16_t crc, uint8_t byte) {
#if defined(__AVR__)
  uint8_t t;
  // volatile, as avr-libc's: without it GCC takes crc16() for a pure function and its callers grow.
  __asm__ __volatile__(
      "eor  %B0, %2\n\t"  // x
      "mov  %1, %B0\n\t"
      "swap %1\n\t"
      "andi %1, 0x0F\n\t"
      "eor  %B0, %1\n\t"  // x ^= x >> 4
      "mov  %1, %B0\n\t"
      "swap %1\n\t"
      "andi %1, 0xF0\n\t"  // (x << 4) & 0xFF
      "eor  %A0, %1\n\t"
      "lsl  %1\n\t"  // (x << 5) & 0xFF
      "eor  %1, %B0\n\t"  // the new low byte: (x << 5) ^ x
      "lsr  %B0\n\t"
      "lsr  %B0\n\t"
      "lsr  %B0\n\t"
      "eor  %B0, %A0\n\t"  // the new high byte: the old low one ^ (x << 4) ^ (x >> 3)
      "mov  %A0, %1"
      : "+r"(crc), "=&d"(t)
      : "r"(byte));
  return crc;
#else
  crc = (uint16_t)((crc >> 8) | (crc << 8));
  crc ^= byte;
  crc ^= (uint16_t)((crc & 0xFF) >> 4);
  crc ^= (uint16_t)(crc << 12);
  crc ^= (uint16_t)((crc & 0xFF) << 5);
  return crc;
#endif
}

inline uint16_t crc16(const uint8_t* data, size_t len, uint16_t crc = kCrcInit) {
  for (size_t i = 0; i < len; ++i) crc = crc16Update(crc, data[i]);
  return crc;
}

}  // namespace hubwire

#endif
