// The sketch the large-value and List suites run (large_sketch.cpp), with the helpers and the
// fixture they share: a 1 KB struct, Lists as variables, a control's and actions' arguments and
// results, all in one table (a program holds one table with large values).
#ifndef HUBWIRE_TEST_LARGE_SKETCH_H
#define HUBWIRE_TEST_LARGE_SKETCH_H

#include <gtest/gtest.h>

#include "fakes.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"
#include "hubwire/wire/bytes.h"

namespace large_sketch {

using namespace hubwire;
using namespace hubwire::test;

struct Kilo {
  uint32_t words[200];
  float f[56];
};
extern Kilo kilo;
extern List<int16_t, 8> path;
extern List<uint8_t, 200> blob;
extern int kiloChanges, pathChanges, stepsCalls, pinsCalls;
extern List<int16_t, 4> lastSteps;
const ChannelTable& table();
uint16_t features();  // what HUBWIRE_CHANNELS worked out

const uint8_t kKilo = 1, kPath = 2, kBlob = 3, kSteps = 4, kSum = 5, kTrues = 6, kSmall = 7, kPins = 8, kRecent = 9;

Bytes operator+(Bytes a, const Bytes& b);
Bytes bytesOf(const void* p, size_t n);
// The F payloads carrying (type, payload) for a receiver taking max bytes a frame.
std::vector<Bytes> split(uint8_t type, const Bytes& payload, size_t max = HUBWIRE_MAX_PAYLOAD);
Bytes pattern(size_t n, uint8_t salt);
// Reassembles the device's fragments of one message; checks they come offset 0 first, contiguous,
// each of the given data size but the last.
Bytes reassemble(const std::vector<RxFrame>& frames, uint8_t type, uint8_t seq, uint8_t id, size_t per);

class Large : public ::testing::Test {
 protected:
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  hubwire::Session device{port};

  void SetUp() override {
    memset(&kilo, 0, sizeof(kilo));
    path.clear();
    blob.clear();
    kiloChanges = pathChanges = stepsCalls = 0;
    ASSERT_TRUE(device.begin(table(), 9));
  }

  void link(uint16_t hubMax = 255) {
    Bytes hello = hubHello(3);
    storeU16(&hello[6], hubMax);
    sendFrame(stream, '*', 0, 0, hello);
    device.update();
    ASSERT_TRUE(device.linked());
    device.update();
    drain(stream);
  }

  // A new session on the same port, linked by a hub that takes payloads of up to hubMax bytes.
  void relink(uint16_t hubMax) {
    stream.in.clear();
    device.~Session();
    new (&device) hubwire::Session(port);
    SetUp();
    link(hubMax);
  }

  // Puts pattern(1024, salt) into kilo; those bytes.
  Bytes fillKilo(uint8_t salt) {
    Bytes value = pattern(sizeof(kilo), salt);
    memcpy(&kilo, value.data(), sizeof(kilo));
    return value;
  }

  // Sends frames; returns what the device sent, heartbeats aside.
  std::vector<RxFrame> send(uint8_t seq, uint8_t id, const std::vector<Bytes>& fragments) {
    for (auto& f : fragments) sendFrame(stream, 'F', seq, id, f);
    return run();
  }
  std::vector<RxFrame> run() {
    while (!stream.in.empty()) device.update();
    std::vector<RxFrame> got;
    for (auto& f : drain(stream))
      if (f.type != 'H') got.push_back(f);
    return got;
  }
  uint16_t dropped() { return device.counters().dropped; }
};

}  // namespace large_sketch

#endif
