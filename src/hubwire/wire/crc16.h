// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection): check value 0x29B1 for "123456789".
#ifndef HUBWIRE_WIRE_CRC16_H
#define HUBWIRE_WIRE_CRC16_H

#include <stddef.h>
#include <stdint.h>

#if defined(__AVR__)
#include <util/crc16.h>
#endif

namespace hubwire {

const uint16_t kCrcInit = 0xFFFF;

// One byte into the CRC. Table-free: the shift-and-xor form costs no flash table and, on AVR,
// avr-libc's hand-written assembly of the same polynomial is used.
inline uint16_t crc16Update(uint16_t crc, uint8_t byte) {
#if defined(__AVR__)
  return _crc_xmodem_update(crc, byte);
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
