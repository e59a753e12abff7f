// The device session built with config.h settings at the ends of their ranges (CMakeLists.txt
// compiles this suite with its own copy of the core and the definitions below); test_session
// covers the defaults. Each test names the setting it is about.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "fakes.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

#if HUBWIRE_MAX_STREAMS != 0 || HUBWIRE_MAX_CHANNELS != 254
#error "test_limits is built with -DHUBWIRE_MAX_STREAMS=0 -DHUBWIRE_MAX_CHANNELS=254"
#endif

using namespace hubwire;
using namespace hubwire::test;

namespace {

uint16_t level;

// 254 channels, declared as a sketch would, named "level" + their index in 8 binary digits
// (level00000000 .. level11111101): LEVELS_n(p) declares 2^n channels named p + n binary digits.
#define LEVEL(name) expose(#name, level).streamable()
#define LEVELS_1(p) LEVEL(p##0), LEVEL(p##1)
#define LEVELS_2(p) LEVELS_1(p##0), LEVELS_1(p##1)
#define LEVELS_3(p) LEVELS_2(p##0), LEVELS_2(p##1)
#define LEVELS_4(p) LEVELS_3(p##0), LEVELS_3(p##1)
#define LEVELS_5(p) LEVELS_4(p##0), LEVELS_4(p##1)
#define LEVELS_6(p) LEVELS_5(p##0), LEVELS_5(p##1)
#define LEVELS_7(p) LEVELS_6(p##0), LEVELS_6(p##1)
HUBWIRE_CHANNELS(most, "limits", LEVELS_7(level0), LEVELS_6(level10), LEVELS_5(level110), LEVELS_4(level1110),
                 LEVELS_3(level11110), LEVELS_2(level111110), LEVELS_1(level1111110));
HUBWIRE_CHANNELS(one, "limits", LEVEL(level));

class Limits : public ::testing::Test {
 protected:
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  Session device{port};

  // Starts the session with a hub.
  void link() {
    ASSERT_TRUE(device.begin(one));
    sendFrame(stream, '*', 0, 0, hubHello(99));
    device.update();
    drain(stream);
    ASSERT_TRUE(device.linked());
  }
};

// HUBWIRE_MAX_CHANNELS=254: the largest setting takes 254 channels, numbered 1..254 in the one-byte
// channel id. The 255th (and a 256th, which would wrap the id to 0) fails to compile
// (test/compile_fail, cases 21..23).
TEST_F(Limits, LargestChannelLimitTakes254Channels) {
  ASSERT_TRUE(device.begin(most));
  EXPECT_EQ(device.channelCount(), 254);
  sendFrame(stream, '*', 0, 0, hubHello(99));
  device.update();
  Bytes hello = drain(stream).at(0).payload;
  ASSERT_TRUE(device.linked());
  level = 0xBEEF;  // every channel reads it: the last id answers, the next one is unknown
  sendFrame(stream, 'R', 1, 254, Bytes());
  sendFrame(stream, 'R', 2, 255, Bytes());
  device.update();
  std::vector<RxFrame> answers;
  for (auto& f : drain(stream))
    if (f.type != 'H') answers.push_back(f);
  ASSERT_EQ(answers.size(), 2u);
  EXPECT_EQ(answers[0].type, 'r');
  EXPECT_EQ(answers[0].payload, le<uint16_t>(0xBEEF));
  EXPECT_EQ(answers[1].type, kMsgNak);
  EXPECT_EQ(answers[1].payload, Bytes{kErrUnknownChannel});
  // The descriptor lists them all, in declaration order.
  std::string json;
  for (uint8_t seq = 3; json.size() < device.descriptorLength(); ++seq) {
    Bytes req(3);
    storeU16(&req[0], (uint16_t)json.size());
    req[2] = 255;
    sendFrame(stream, 'J', seq, 0, req);
    device.update();
    size_t before = json.size();
    for (auto& f : drain(stream))
      if (f.type == 'J') json.append(f.payload.begin() + 4, f.payload.end());
    ASSERT_GT(json.size(), before);
  }
  auto d = nlohmann::json::parse(json);
  ASSERT_EQ(d["ch"].size(), 254u);
  EXPECT_EQ(d["ch"][0]["n"], "level00000000");
  EXPECT_EQ(d["ch"][253]["id"], 254);
  EXPECT_EQ(d["ch"][253]["n"], "level11111101");
  // The hash hello carries, worked out by the compiler, is the hash of what was sent.
  uint32_t h = kFnvOffset;
  for (unsigned char c : json) h = fnv1a(h, c);
  EXPECT_EQ(device.descriptorHash(), h);
  // So is the digest, the largest the compiler works out here: 12,619 bytes, 198 SHA-256 blocks.
  //   ch = ['{"id":%d,"n":"level%s","a":"rs","t":"u16"}' % (i + 1, format(i, "08b")) for i in range(254)]
  //   hashlib.sha256(('{"p":1,"n":"limits","ch":[' + ",".join(ch) + "]}").encode()).hexdigest()[:32]
  EXPECT_EQ(json.size(), 12619u);
  ASSERT_EQ(hello.size(), (size_t)kHelloDigestEnd);
  EXPECT_EQ(toHex(&hello[kHelloSize], kDigestSize), "e9a0341bfaff9d6f027ea9050c99d6d7");
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
