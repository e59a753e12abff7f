// The device session built with config.h settings at the ends of their ranges (CMakeLists.txt
// compiles this suite with its own copy of the core and the definitions below); test_session
// covers the defaults. Each test names the setting it is about.
#include <gtest/gtest.h>

#include "fakes.h"
#include "hubwire/session/device.h"

#if HUBWIRE_MAX_STREAMS != 0 || HUBWIRE_MAX_CHANNELS != 254
#error "test_limits is built with -DHUBWIRE_MAX_STREAMS=0 -DHUBWIRE_MAX_CHANNELS=254"
#endif

using namespace hubwire;
using namespace hubwire::test;

namespace {

Device* dut;
uint16_t level;
int declaredCount;  // how many channels declare() makes
void declarations() {
  for (int i = 0; i < declaredCount; ++i) dut->expose("level", level).streamable();
}

class Limits : public ::testing::Test {
 protected:
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  Device device{port};

  void SetUp() override {
    dut = &device;
    declaredCount = 1;
  }

  // Starts the session with a hub.
  void link() {
    ASSERT_TRUE(device.begin("limits", declarations));
    sendFrame(stream, '*', 0, 0, hubHello(99));
    device.update();
    drain(stream);
    ASSERT_TRUE(device.linked());
  }
};

// HUBWIRE_MAX_CHANNELS=254: the largest setting still reports the first channel too many by its id,
// which must fit the one-byte channel id (a 256th declaration would wrap to 0).
TEST_F(Limits, LargestChannelLimitReportsTheChannelTooMany) {
  declaredCount = 254;
  ASSERT_TRUE(device.begin("limits", declarations));
  EXPECT_EQ(device.channelCount(), 254);
  for (int extra : {255, 256, 300}) {
    declaredCount = extra;
    EXPECT_FALSE(device.begin("limits", declarations)) << extra;
    EXPECT_EQ(device.error(), kSetupTooManyChannels) << extra;
    EXPECT_EQ(device.errorChannel(), 255) << extra;
  }
}

// HUBWIRE_MAX_STREAMS=0: no slots, so a subscription is BUSY, while a cancel (interval 0) and every
// other answer behave as with slots.
TEST_F(Limits, NoStreamSlotsAnswerBusyAndAcceptCancel) {
  link();
  sendFrame(stream, 'S', 1, 1, le<uint16_t>(100));
  sendFrame(stream, 'S', 2, 1, le<uint16_t>(0));
  sendFrame(stream, 'S', 3, 2, le<uint16_t>(100));
  device.update();
  std::vector<RxFrame> answers;
  for (auto& f : drain(stream))
    if (f.type != 'H') answers.push_back(f);
  ASSERT_EQ(answers.size(), 3u);
  EXPECT_EQ(answers[0].type, kMsgNak);
  EXPECT_EQ(answers[0].payload, Bytes{kErrBusy});
  EXPECT_EQ(answers[1].type, kMsgAck);
  EXPECT_EQ(answers[1].payload, le<uint16_t>(0));
  EXPECT_EQ(answers[2].type, kMsgNak);
  EXPECT_EQ(answers[2].payload, Bytes{kErrUnknownChannel});
  clock.now += 1000;
  device.update();
  for (auto& f : drain(stream)) EXPECT_NE(f.type, 'D');
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
