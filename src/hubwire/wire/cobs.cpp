#include "cobs.h"

namespace hubwire {

size_t cobsEncode(const uint8_t* in, size_t n, uint8_t* out) {
  size_t codeAt = 0, o = 1;
  uint8_t code = 1;
  for (size_t i = 0; i < n; ++i) {
    if (in[i] == 0) {
      out[codeAt] = code;
      codeAt = o++;
      code = 1;
      continue;
    }
    out[o++] = in[i];
    if (++code == 0xFF && i + 1 < n) {  // a full block of 254 non-zero bytes: no implied zero
      out[codeAt] = code;
      codeAt = o++;
      code = 1;
    }
  }
  out[codeAt] = code;
  return o;
}

bool cobsDecode(const uint8_t* in, size_t n, uint8_t* out, size_t cap, size_t* outLen) {
  size_t i = 0, o = 0;
  while (i < n) {
    uint8_t code = in[i++];
    if (code == 0 || i + code - 1 > n) return false;
    for (uint8_t k = 1; k < code; ++k) {
      if (in[i] == 0 || o >= cap) return false;
      out[o++] = in[i++];
    }
    if (code != 0xFF && i < n) {
      if (o >= cap) return false;
      out[o++] = 0;
    }
  }
  *outLen = o;
  return true;
}

}  // namespace hubwire
