// Test doubles for the core's seams (the frame helpers are in frames.h).
#ifndef HUBWIRE_TEST_FAKES_H
#define HUBWIRE_TEST_FAKES_H

#include <deque>

#include "frames.h"
#include "hubwire/port.h"

namespace hubwire {
namespace test {

class FakeStream {
 public:
  int read() {
    if (in.empty()) return -1;
    int c = in.front();
    in.pop_front();
    return c;
  }
  void write(const uint8_t* data, size_t len) { out.insert(out.end(), data, data + len); }

  std::deque<uint8_t> in;  // bytes for the device to read
  Bytes out;               // bytes the device wrote
  size_t room = 4096;
};

class FakeClock {
 public:
  uint32_t micros() { return us ? us : now * 1000u; }
  uint32_t now = 1000;
  uint32_t us = 0;  // set to pin micros() independently of millis()
};

}  // namespace test

// The tests' binding of the core's seam (functions in fakes.cpp).
class Port {
 public:
  Port(test::FakeStream& s, test::FakeClock& c) : stream(s), clock(c) {}
  test::FakeStream& stream;
  test::FakeClock& clock;
  test::Bytes boardId;  // what portBoardId() reports (empty: the board has no id)
};

}  // namespace hubwire

#endif
