// A program with one HUBWIRE_CHANNELS (as a sketch is): the macro defines hubwire::sketchFeatures
// from the declarations, and the session, which tests it, answers as before for what the sketch
// uses and refuses what it does not declare. Other suites define HUBWIRE_ALL_FEATURES (several
// tables a program): there the library's default, every feature, holds (test_tables).
#include <gtest/gtest.h>

#include "fakes.h"
#include "hubwire/channels/declare.h"
#include "hubwire/features.h"
#include "hubwire/session/session.h"
#include "hubwire/wire/bytes.h"

using namespace hubwire;
using namespace hubwire::test;

namespace {

uint16_t level = 7;
bool lamp;
void setLamp(bool on) { lamp = on; }

}  // namespace

// At file scope, as in a sketch: the macro defines hubwire::sketchFeatures.
HUBWIRE_CHANNELS(few, "few", expose("level", level).range(0, 100).writable(), control("lamp", setLamp));

namespace {

struct Device {
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  hubwire::Session session{port};
  uint8_t seq = 0;
  Device() {
    EXPECT_TRUE(session.begin(few, 3));
    sendFrame(stream, '*', 0, 0, hubHello(9));
    session.update();
    drain(stream);
  }
  RxFrame ask(uint8_t type, uint8_t id, const Bytes& payload = Bytes()) {
    sendFrame(stream, type, ++seq, id, payload);  // a new seq: not a retry
    session.update();
    std::vector<RxFrame> got = drain(stream);
    EXPECT_EQ(got.size(), 1u);
    return got.empty() ? RxFrame() : got[0];
  }
};

TEST(Features, TheMacroDefinesTheSketchsFeatures) {
  EXPECT_EQ(hubwire_channels_few::features, kUsesRanges | kUsesWrites | kUsesReads | kUsesCalls);
  EXPECT_EQ(sketchFeatures, hubwire_channels_few::features);
  EXPECT_FALSE(uses(kUsesStreams | kUsesEvents | kUsesFailsafes | kUsesStrings | kUsesStructs | kUsesReturns));
}

// ... and hubwire::sketchTable, the table as a constant the session reads in place of a copy.
TEST(Features, TheMacroDefinesTheSketchsTable) {
  EXPECT_EQ(sketchTableAt, &few);
  EXPECT_EQ(sketchTable.json, few.json);
  EXPECT_EQ(sketchTable.hash, few.hash);
  EXPECT_EQ(sketchTable.jsonLength, few.jsonLength);
  EXPECT_EQ(sketchTable.channels, few.channels);
  EXPECT_EQ(sketchTable.count, 2);
  Device d;
  EXPECT_EQ(d.session.channelCount(), 2);
  EXPECT_EQ(d.session.descriptorHash(), few.hash);
  EXPECT_EQ(d.session.descriptorLength(), few.jsonLength);
}

// With one table in the program the session starts that one only: another (made by hand, as no
// second HUBWIRE_CHANNELS can be) is refused, even with the same contents.
TEST(Features, ATableOtherThanTheSketchsIsRefused) {
  FakeStream stream;
  FakeClock clock;
  Port port(stream, clock);
  hubwire::Session session(port);
  const ChannelTable copy = few;
  EXPECT_FALSE(session.begin(copy));
  EXPECT_EQ(session.error(), kSetupNoDeclarations);
  EXPECT_EQ(session.channelCount(), 0);
  clock.now += HUBWIRE_ANNOUNCE_MS;
  session.update();
  EXPECT_TRUE(stream.out.empty());  // silent, as after any refused begin()
  EXPECT_TRUE(session.begin(few));
  EXPECT_EQ(session.error(), kSetupOk);
}

TEST(Features, UsedFeaturesWorkAsBefore) {
  Device d;
  ASSERT_TRUE(d.session.linked());
  RxFrame r = d.ask('R', 1);
  EXPECT_EQ(r.type, 'r');
  EXPECT_EQ(r.payload, Bytes({7, 0}));
  EXPECT_EQ(d.ask('C', 1, Bytes({200, 0})).type, 0x15);  // out of range: ranges are checked
  EXPECT_EQ(d.ask('C', 1, Bytes({50, 0})).type, 0x07);
  EXPECT_EQ(level, 50);
  EXPECT_EQ(d.ask('C', 2, Bytes({1})).type, 0x07);
  EXPECT_TRUE(lamp);
}

TEST(Features, FeaturesNotDeclaredAreRefused) {
  Device d;
  RxFrame s = d.ask('S', 1, Bytes({100, 0}));
  EXPECT_EQ(s.type, 0x15);
  EXPECT_EQ(s.payload, Bytes({kErrNotStreamable}));
  RxFrame r = d.ask('R', 2);  // a control is not readable
  EXPECT_EQ(r.type, 0x15);
  EXPECT_EQ(r.payload, Bytes({kErrNotReadable}));
  Event<uint8_t> undeclared = {};
  EXPECT_FALSE(d.session.emit(undeclared, 1));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
