// Consistent Overhead Byte Stuffing: turns a frame into bytes without 0x00, so 0x00 can end it.
#ifndef HUBWIRE_WIRE_COBS_H
#define HUBWIRE_WIRE_COBS_H

#include <stddef.h>
#include <stdint.h>

namespace hubwire {

// Largest encoding of n bytes (without the 0x00 delimiter).
inline size_t cobsMaxEncoded(size_t n) { return n + n / 254 + 1; }

// Encodes n bytes into out (room for cobsMaxEncoded(n)); returns the encoded length.
size_t cobsEncode(const uint8_t* in, size_t n, uint8_t* out);

// Decodes an encoded block (no delimiter) into out; false when malformed or longer than cap.
bool cobsDecode(const uint8_t* in, size_t n, uint8_t* out, size_t cap, size_t* outLen);

}  // namespace hubwire

#endif
