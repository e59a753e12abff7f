// The tests' binding of the core's seam (functions in fakes.cpp): a stream and a clock the test
// drives. The session keeps a copy of its Port, so the Port only refers to them.
#ifndef HUBWIRE_TEST_PORT_FAKE_H
#define HUBWIRE_TEST_PORT_FAKE_H

#include <stddef.h>
#include <stdint.h>

#include <deque>
#include <vector>

namespace hubwire {
namespace test {

typedef std::vector<uint8_t> Bytes;

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
  Bytes boardId;  // what portBoardId() reports (empty: the board has no id)
};

class FakeClock {
 public:
  uint32_t micros() { return us ? us : now * 1000u; }
  uint32_t now = 1000;
  uint32_t us = 0;  // set to pin micros() independently of millis()
};

}  // namespace test

class Port {
 public:
  Port(test::FakeStream& s, test::FakeClock& c) : stream(s), clock(c) {}
  test::FakeStream& stream;
  test::FakeClock& clock;
};

}  // namespace hubwire

#endif
