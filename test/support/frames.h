// A small "hub" for tests: frames to and from a device's stream. Any stream with the fakes' shape
// works: `in`, a deque the device reads, and `out`, a vector of what it wrote. No Port binding
// here, so suites that bind the seam another way (test_arduino_face) can use it too.
#ifndef HUBWIRE_TEST_FRAMES_H
#define HUBWIRE_TEST_FRAMES_H

#include <cstring>
#include <string>
#include <vector>

#include "hubwire/wire/bytes.h"
#include "hubwire/wire/frame.h"

namespace hubwire {
namespace test {

typedef std::vector<uint8_t> Bytes;

struct RxFrame {
  uint8_t type, seq, id;
  Bytes payload;
};

// Decodes everything the device wrote so far (s.out) into frames, and clears it.
template <typename Stream>
std::vector<RxFrame> drain(Stream& s, LinkCounters* counters = nullptr) {
  static uint8_t buf[HUBWIRE_RAW_FRAME_SIZE(255)];
  FrameReceiver rx(buf, sizeof(buf));
  std::vector<RxFrame> frames;
  for (uint8_t b : s.out) {
    if (rx.feed(b)) {
      const Frame& f = rx.frame();
      frames.push_back(RxFrame{f.type, f.seq, f.id, Bytes(f.payload, f.payload + f.len)});
    }
  }
  if (counters) *counters = rx.counters;
  s.out.clear();
  return frames;
}

// A hub's hello (PROTOCOL 3.1): it accepts 255-byte payloads and beats every `beat` ms.
inline Bytes hubHello(uint32_t nonce, uint8_t flags = 0, uint8_t version = 1, uint16_t beat = 250) {
  Bytes p(16, 0);
  p[0] = version;
  p[1] = flags;
  storeU32(&p[2], nonce);
  storeU16(&p[6], 255);
  storeU16(&p[8], beat);
  return p;
}

template <typename Stream>
void sendFrame(Stream& s, uint8_t type, uint8_t seq, uint8_t id, const Bytes& payload = Bytes()) {
  uint8_t out[300];
  size_t n = encodeFrame(type, seq, id, payload.data(), (uint8_t)payload.size(), out);
  s.in.insert(s.in.end(), out, out + n);
}

template <typename T>
Bytes le(T v) {
  Bytes b(sizeof(T));
  std::memcpy(b.data(), &v, sizeof(T));
  return b;
}

inline Bytes hex(const std::string& h) {
  Bytes b;
  for (size_t i = 0; i + 1 < h.size(); i += 2) b.push_back((uint8_t)std::stoul(h.substr(i, 2), nullptr, 16));
  return b;
}

inline std::string toHex(const uint8_t* p, size_t n) {
  static const char* d = "0123456789abcdef";
  std::string s;
  for (size_t i = 0; i < n; ++i) {
    s += d[p[i] >> 4];
    s += d[p[i] & 15];
  }
  return s;
}

}  // namespace test
}  // namespace hubwire

#endif
