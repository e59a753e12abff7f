// The Arduino face (src/Hubwire.h, src/HubwireArduino.cpp) over a Stream that behaves like a
// board's serial port, built against the emulator's stand-in Arduino.h. CMakeLists.txt builds this
// suite without test/support/fakes.cpp: here the seam is bound by the library's own Arduino binding.
#include <gtest/gtest.h>

#include <deque>
#include <type_traits>
#include <vector>

#include "Hubwire.h"
#include "frames.h"

namespace {

using namespace hubwire::test;

uint32_t nowMs = 1000;

// A serial port with a transmit buffer of `capacity` bytes, which availableForWrite() reports as
// the Uno's HardwareSerial does (63 at most there). Bytes written stay queued until the test
// says the UART has sent them.
class BufferedSerial : public Stream {
 public:
  explicit BufferedSerial(int capacity) : capacity_(capacity) {}
  int available() override { return (int)in.size(); }
  int read() override {
    if (in.empty()) return -1;
    int c = in.front();
    in.pop_front();
    return c;
  }
  int peek() override { return in.empty() ? -1 : in.front(); }
  size_t write(uint8_t b) override { return write(&b, 1); }
  size_t write(const uint8_t* data, size_t len) override {
    queued_ += (int)len;
    out.insert(out.end(), data, data + len);
    return len;
  }
  int availableForWrite() override {
    if (capacity_ == 0) return 0;  // a core that does not implement it
    return queued_ >= capacity_ ? 0 : capacity_ - queued_;
  }
  void uartSent(int n) { queued_ = n >= queued_ ? 0 : queued_ - n; }
  void uartSentAll() { queued_ = 0; }

  std::deque<uint8_t> in;
  std::vector<uint8_t> out;

 private:
  int capacity_;
  int queued_ = 0;
};

uint16_t level = 7;
HUBWIRE_CHANNELS(channels, "face", expose("level", level).streamable());

// The frame types the device wrote since the last call.
std::vector<uint8_t> sentTypes(BufferedSerial& s) {
  std::vector<uint8_t> types;
  for (const RxFrame& f : drain(s)) types.push_back(f.type);
  return types;
}

size_t count(const std::vector<uint8_t>& types, uint8_t type) {
  size_t n = 0;
  for (uint8_t t : types) n += t == type;
  return n;
}

// Links a hub and subscribes it to `level` every 10 ms.
void linkAndSubscribe(Hubwire& hub, BufferedSerial& serial) {
  ASSERT_TRUE(hub.begin(channels));
  sendFrame(serial, '*', 0, 0, hubHello(42));
  hub.update();
  ASSERT_TRUE(hub.linked());
  sendFrame(serial, 'S', 1, 1, {10, 0});
  hub.update();
  ASSERT_EQ(count(sentTypes(serial), 0x07), 1u);  // the subscription's ACK
  serial.uartSentAll();
}

// A sample frame here is 11 bytes on the wire. A port whose whole transmit buffer is smaller
// (8 bytes) must still get samples: waiting cannot make more room than an empty buffer.
TEST(ArduinoFace, SamplesLargerThanTheWholeTransmitBufferAreStillSent) {
  BufferedSerial serial(8);
  Hubwire hub(serial);
  linkAndSubscribe(hub, serial);
  size_t samples = 0;
  for (int i = 0; i < 5; ++i) {
    nowMs += 10;
    hub.update();
    samples += count(sentTypes(serial), 'D');
    serial.uartSentAll();
  }
  EXPECT_GE(samples, 4u);
}

// While the buffer is busy and can still drain, a sample waits for room instead of blocking.
TEST(ArduinoFace, SampleWaitsWhileTheTransmitBufferCanStillDrain) {
  BufferedSerial serial(64);
  Hubwire hub(serial);
  linkAndSubscribe(hub, serial);
  nowMs += 10;
  hub.update();  // the port reported its whole buffer: the sample goes
  ASSERT_EQ(count(sentTypes(serial), 'D'), 1u);
  serial.uartSentAll();
  uint8_t filler[60] = {};
  serial.write(filler, sizeof(filler));  // the sketch's own output fills the buffer: 4 bytes free
  serial.out.clear();
  nowMs += 10;
  hub.update();
  EXPECT_EQ(count(sentTypes(serial), 'D'), 0u);
  serial.uartSent(30);
  hub.update();
  EXPECT_EQ(count(sentTypes(serial), 'D'), 1u);
}

// A core that never implements availableForWrite() (always 0): room is unknown, samples go.
TEST(ArduinoFace, SamplesGoWhenThePortNeverReportsRoom) {
  BufferedSerial serial(0);
  Hubwire hub(serial);
  linkAndSubscribe(hub, serial);
  nowMs += 10;
  hub.update();
  EXPECT_EQ(count(sentTypes(serial), 'D'), 1u);
}

}  // namespace

uint32_t millis() { return nowMs; }
uint32_t micros() { return nowMs * 1000u; }

// One session per port: copying one (which would answer the same hub twice) does not compile.
TEST(Copying, IsRefused) {
  EXPECT_FALSE(std::is_copy_constructible<Hubwire>::value);
  EXPECT_FALSE(std::is_copy_assignable<Hubwire>::value);
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
