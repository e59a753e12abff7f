// Large values in fragments (docs/PROTOCOL.md 12) on the device: a 1 KB struct written, read and
// streamed; reassembly and every way it is abandoned; capacity; the duplicate memory for a retried
// large control; fragments sized to what the hub accepts; large Lists written and passed.
#include <algorithm>

#include <nlohmann/json.hpp>

#include "large_sketch.h"

using namespace large_sketch;

namespace {

TEST_F(Large, DeclarationsSizeTheOneBuffer) {
  EXPECT_EQ((HubwireLarge<true, void>::capacity), 1024);  // kilo; blob and sum take 201
  EXPECT_NE((HubwireLarge<true, void>::state), nullptr);
  EXPECT_EQ(features() & (kUsesLarge | kUsesLists), kUsesLarge | kUsesLists);
  auto json = nlohmann::json::parse(std::string(table().json, table().jsonLength));
  auto& ch = json["ch"];
  EXPECT_EQ(ch[kPath - 1]["t"], "i16");
  EXPECT_EQ(ch[kPath - 1]["vc"], 8);
  EXPECT_FALSE(ch[kPath - 1].contains("c"));
  EXPECT_EQ(ch[kSum - 1]["t"], "u16");
  EXPECT_EQ(ch[kSum - 1]["vc"], 100);
  EXPECT_EQ(ch[kSum - 1]["rt"], "u32");
  EXPECT_EQ(ch[kSmall - 1]["c"], 4);
  EXPECT_EQ(ch[kPins - 1]["rt"], "u8");
  EXPECT_EQ(ch[kPins - 1]["rvc"], 3);
  EXPECT_EQ(ch[kPins - 1]["t"], "u8");
  EXPECT_FALSE(ch[kPins - 1].contains("vc"));
  EXPECT_EQ(ch[kRecent - 1]["rt"], "i16");
  EXPECT_EQ(ch[kRecent - 1]["rvc"], 3);
  EXPECT_FALSE(ch[kKilo - 1].contains("rvc"));
}

TEST_F(Large, AKilobyteStructIsWrittenInFragmentsAndAppliedOnce) {
  link();
  Bytes value = pattern(1024, 1);
  auto fragments = split('C', value);
  ASSERT_EQ(fragments.size(), 38u);  // 1024 / 27
  auto got = send(0x40, kKilo, fragments);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  EXPECT_EQ(got[0].seq, 0x40);
  EXPECT_EQ(got[0].id, kKilo);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), value);
  EXPECT_EQ(kiloChanges, 1);
}

TEST_F(Large, ARetriedLargeControlIsAnsweredFromMemoryNotAppliedTwice) {
  link();
  Bytes first = pattern(1024, 2), other = pattern(1024, 3);
  auto got = send(0x41, kKilo, split('C', first));
  ASSERT_EQ(got.size(), 1u);
  // the retry (same seq) carries other bytes: were it applied, kilo would hold them
  got = send(0x41, kKilo, split('C', other));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  EXPECT_EQ(got[0].seq, 0x41);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), first);
  EXPECT_EQ(kiloChanges, 1);
  got = send(0x42, kKilo, split('C', other));  // a new seq is a new write
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), other);
  EXPECT_EQ(kiloChanges, 2);
}

TEST_F(Large, OutOfOrderRepeatedOrMissingFragmentsNeverCompleteTheValue) {
  link();
  Bytes value = pattern(1024, 4);
  auto f = split('C', value);
  struct Case {
    const char* what;
    std::vector<Bytes> frames;
    int dropped;
  } cases[] = {
      {"swapped", {f[0], f[2], f[1]}, 1},  // the one past the gap; the next one in order is kept
      {"repeated", {f[0], f[1], f[1], f[2]}, 0},  // a fragment it has is skipped
      {"missing last", std::vector<Bytes>(f.begin(), f.end() - 1), 0},
      {"missing first", std::vector<Bytes>(f.begin() + 1, f.end()), (int)f.size() - 1},
  };
  uint8_t seq = 0x50;
  for (auto& c : cases) {
    SCOPED_TRACE(c.what);
    uint16_t before = dropped();
    auto got = send(seq++, kKilo, c.frames);  // each case a message of its own
    EXPECT_TRUE(got.empty());
    EXPECT_EQ(dropped() - before, c.dropped);
    EXPECT_EQ(kiloChanges, 0);
    EXPECT_EQ(kilo.words[0], 0u);
  }
  // the hub's retry of the whole value goes through
  auto got = send(0x60, kKilo, f);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), value);
}

// Each try of a large control (same seq, same bytes: PROTOCOL.md 4.1) adds to what the tries before
// it brought, so a long value gets through a lossy line in tries in proportion to its length.
TEST_F(Large, ATryCarriesOnWhereTheOneBeforeLeftOff) {
  link();
  Bytes value = pattern(1024, 8);
  auto f = split('C', value);
  auto without = [&](std::initializer_list<size_t> lost) {
    std::vector<Bytes> out;
    for (size_t i = 0; i < f.size(); ++i)
      if (std::find(lost.begin(), lost.end(), i) == lost.end()) out.push_back(f[i]);
    return out;
  };
  EXPECT_TRUE(send(0x61, kKilo, without({10, 30})).empty());
  EXPECT_TRUE(send(0x61, kKilo, without({5, 25})).empty());  // 5 it has; 10 .. 24 it takes now
  EXPECT_EQ(kiloChanges, 0);
  auto got = send(0x61, kKilo, without({3, 20}));  // only what it had already is lost this time
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), value);
  EXPECT_EQ(kiloChanges, 1);
}

// A retry of a large control that was applied but whose answer was lost: its last fragment is
// enough to have it answered again (not applied again), whatever of the rest is lost.
TEST_F(Large, ARetryOfAnAnsweredLargeControlIsAnsweredFromItsLastFragment) {
  link();
  Bytes value = pattern(1024, 11);
  auto f = split('C', value);
  ASSERT_EQ(send(0x64, kKilo, f).size(), 1u);  // applied; say its ACK was lost
  auto got = send(0x64, kKilo, std::vector<Bytes>(f.end() - 1, f.end()));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  EXPECT_EQ(got[0].seq, 0x64);
  EXPECT_EQ(kiloChanges, 1);
  EXPECT_TRUE(send(0x64, kKilo, std::vector<Bytes>(f.begin(), f.end() - 1)).empty());  // no last one: no answer
  EXPECT_EQ(kiloChanges, 1);
}

// A control between two tries ends the one in progress: a later message that happens to take the
// same seq, id and length never completes it with bytes of its own.
TEST_F(Large, AnotherControlEndsAHalfReassembledOne) {
  link();
  auto first = split('C', pattern(1024, 9));
  auto other = split('C', pattern(1024, 10));
  EXPECT_TRUE(send(0x62, kKilo, std::vector<Bytes>(first.begin(), first.begin() + 10)).empty());
  sendFrame(stream, 'C', 0x63, kSmall, Bytes{1, 2, 3, 4});
  ASSERT_EQ(run().size(), 1u);
  EXPECT_TRUE(send(0x62, kKilo, std::vector<Bytes>(other.begin() + 10, other.end())).empty());
  EXPECT_EQ(kiloChanges, 0);
  EXPECT_EQ(kilo.words[0], 0u);
}

TEST_F(Large, AFragmentOfAnotherMessageAbandonsTheOneInProgress) {
  link();
  Bytes value = pattern(1024, 5);
  auto f = split('C', value);
  for (size_t i = 0; i < 5; ++i) sendFrame(stream, 'F', 0x51, kKilo, f[i]);
  sendFrame(stream, 'F', 0x52, kKilo, f[5]);  // same offset, other seq
  uint16_t before = dropped();
  for (size_t i = 6; i < f.size(); ++i) sendFrame(stream, 'F', 0x51, kKilo, f[i]);
  auto got = run();
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(dropped() - before, (int)f.size() - 5);
  EXPECT_EQ(kiloChanges, 0);
}

TEST_F(Large, OtherFramesBetweenFragmentsDoNotDisturbTheReassembly) {
  link();
  Bytes value = pattern(1024, 6);
  auto f = split('C', value);
  for (size_t i = 0; i < f.size(); ++i) {
    sendFrame(stream, 'F', 0x53, kKilo, f[i]);
    if (i == 10) sendFrame(stream, 'R', 0x54, kSmall);  // a read between two fragments
    if (i == 20) sendFrame(stream, 'H', 1, 0, Bytes(10, 0));
  }
  auto got = run();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].type, 'r');
  EXPECT_EQ(got[0].seq, 0x54);
  EXPECT_EQ(got[1].type, 0x07);
  EXPECT_EQ(got[1].seq, 0x53);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), value);
}

TEST_F(Large, ATotalOverCapacityIsRefusedAtOnceAndTheRestDropped) {
  link();
  Bytes value = pattern(1025, 7);
  auto f = split('C', value);
  uint16_t before = dropped();
  auto got = send(0x55, kKilo, f);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x15);
  EXPECT_EQ(got[0].seq, 0x55);
  EXPECT_EQ(got[0].id, kKilo);
  EXPECT_EQ(got[0].payload, Bytes{kErrBadLength});
  EXPECT_EQ(dropped() - before, (int)f.size() - 1);
  EXPECT_EQ(kiloChanges, 0);
  // a message the device does not answer (an event) is only counted as overflow
  uint16_t overflow = device.counters().overflow;
  got = send(0x56, kKilo, split('!', pattern(1100, 8)));
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(device.counters().overflow - overflow, 1);
}

TEST_F(Large, AWellFormedLargeMessageThatIsNoControlGetsWhatALongOneWould) {
  link();
  auto got = send(0x57, kKilo, split('R', pattern(40, 9)));  // a read carries nothing
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x15);
  EXPECT_EQ(got[0].seq, 0x57);
  EXPECT_EQ(got[0].payload, Bytes{kErrBadLength});
  uint16_t before = dropped();
  got = send(0x58, kKilo, split('!', pattern(40, 9)));  // the hub's events fit a frame
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(dropped() - before, 1);
  before = dropped();
  got = send(0x59, kKilo, {Bytes{'C', 0, 0, 4, 0}});  // a fragment without data
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(dropped() - before, 1);
}

TEST_F(Large, ALargeReadIsAnsweredInFragmentsSizedForTheHub) {
  for (uint16_t hubMax : {255, 40, 16}) {
    SCOPED_TRACE(hubMax);
    relink(hubMax);
    Bytes value = fillKilo(10);
    sendFrame(stream, 'R', 0x60, kKilo);
    auto got = run();
    size_t per = std::min<size_t>(hubMax, HUBWIRE_MAX_PAYLOAD) - kFragmentHeader;
    EXPECT_EQ(got.size(), (1024 + per - 1) / per);
    for (auto& f : got) EXPECT_LE(f.payload.size(), std::min<size_t>(hubMax, HUBWIRE_MAX_PAYLOAD));
    EXPECT_EQ(reassemble(got, 'r', 0x60, kKilo, per), value);
  }
}

TEST_F(Large, ALargeValueIsStreamedAsFragmentedSamples) {
  link();
  Bytes value = fillKilo(11);
  sendFrame(stream, 'S', 0x61, kKilo, le<uint16_t>(100));
  auto got = run();
  ASSERT_GE(got.size(), 2u);
  EXPECT_EQ(got[0].type, 0x07);
  got.erase(got.begin());
  Bytes sample = reassemble(got, 'D', 0, kKilo, HUBWIRE_MAX_PAYLOAD - kFragmentHeader);
  ASSERT_EQ(sample.size(), 2u + 1024);
  EXPECT_EQ(loadU16(&sample[0]), 0);
  EXPECT_EQ(Bytes(sample.begin() + 2, sample.end()), value);
  // the next sample, interval ms later, with the next sample seq and the time since
  clock.now += 100;
  kilo.words[0] = 0xDEADBEEF;
  device.update();
  got.clear();
  for (auto& f : drain(stream))
    if (f.type != 'H') got.push_back(f);
  sample = reassemble(got, 'D', 1, kKilo, HUBWIRE_MAX_PAYLOAD - kFragmentHeader);
  ASSERT_EQ(sample.size(), 2u + 1024);
  EXPECT_EQ(loadU16(&sample[0]), 100);
  EXPECT_EQ(loadU32(&sample[2]), 0xDEADBEEFu);
}

TEST_F(Large, AListThatIsNotFullGoesInOneFrame) {
  link();
  blob.clear();
  for (uint8_t i = 0; i < 10; ++i) blob.push(i);
  sendFrame(stream, 'R', 0x62, kBlob);
  auto got = run();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 'r');
  EXPECT_EQ(got[0].payload, (Bytes{10, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  for (uint8_t i = 10; i < 200; ++i) blob.push(i);  // full: 201 bytes
  sendFrame(stream, 'R', 0x63, kBlob);
  got = run();
  Bytes whole = reassemble(got, 'r', 0x63, kBlob, HUBWIRE_MAX_PAYLOAD - kFragmentHeader);
  ASSERT_EQ(whole.size(), 201u);
  EXPECT_EQ(whole[0], 200);
  for (uint8_t i = 0; i < 200; ++i) EXPECT_EQ(whole[1 + i], i);
}

TEST_F(Large, ALargeListIsWrittenAndPassedToAnAction) {
  link();
  Bytes list{150};
  for (uint8_t i = 0; i < 150; ++i) list.push_back(i);
  auto got = send(0x64, kBlob, split('C', list));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  ASSERT_EQ(blob.size(), 150);
  EXPECT_EQ(blob[149], 149);
  Bytes arg{100};
  uint32_t want = 0;
  for (uint16_t i = 0; i < 100; ++i) {
    Bytes e = le<uint16_t>((uint16_t)(i * 600));
    arg.insert(arg.end(), e.begin(), e.end());
    want += i * 600u;
  }
  got = send(0x65, kSum, split('C', arg));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 'r');
  EXPECT_EQ(got[0].seq, 0x65);
  EXPECT_EQ(got[0].payload, le<uint32_t>(want));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
