// The flash tables (channels/tables.h): a declared list becomes the descriptor text, its hash and
// one record per channel, with the copies each record points to; and the checks table() makes.
#include <gtest/gtest.h>

#include <string>

#include "hubwire/channels/declare.h"

using namespace hubwire;
using namespace hubwire::declare;

namespace {

struct Pos {
  float x;
  uint8_t ok;
} pos;
uint16_t level;
Event<uint8_t> press;
void setLamp(bool) {}
void changedLate();  // defined after the declarations, as when they sit in a header of their own

}  // namespace

HUBWIRE_CHANNELS(bench, device("bench").firmware("0.1"),
  expose("level", level).writable().range(1, 9).failsafe(1).onChange(changedLate),
  expose("pos", pos, "x:f32,ok:u8"),
  control("lamp", setLamp),
  event("press", press));

namespace {

int lateCalls;
void changedLate() { ++lateCalls; }

std::string text(const ChannelTable& t) { return std::string(t.json, t.jsonLength); }

TEST(Tables, DescriptorTextLengthAndHash) {
  EXPECT_EQ(text(bench), R"({"p":1,"n":"bench","fw":"0.1","ch":[)"
                         R"({"id":1,"n":"level","a":"rw","t":"u16","min":1,"max":9,"fs":1},)"
                         R"({"id":2,"n":"pos","a":"r","t":"struct","f":[{"n":"x","t":"f32"},{"n":"ok","t":"u8"}]},)"
                         R"({"id":3,"n":"lamp","a":"w","t":"bool"},{"id":4,"n":"press","a":"e","t":"u8"}]})");
  uint32_t h = kFnvOffset;
  for (unsigned char c : text(bench)) h = fnv1a(h, c);
  EXPECT_EQ(bench.hash, h);
  EXPECT_EQ(bench.count, 4);
  static_assert(bench.count == 4, "the table is a constant expression");
}

TEST(Tables, OneRecordPerChannelWithItsFlashCopies) {
  const ChannelInfo& lv = bench.channels[0];
  EXPECT_EQ(lv.data, &level);
  EXPECT_EQ(lv.type.code, kU16);
  ASSERT_NE(lv.limits, nullptr);
  EXPECT_EQ(lv.limits->min.bits & 0xFFFF, 1u);
  EXPECT_EQ(lv.limits->failsafe.bits & 0xFFFF, 1u);
  ASSERT_NE(lv.call, nullptr);  // onChange, though declared before it was defined
  (*(void (*const*)())lv.call)();
  EXPECT_EQ(lateCalls, 1);
  const ChannelInfo& ps = bench.channels[1];
  EXPECT_EQ(ps.type.code, kStruct);
  EXPECT_EQ(ps.limits, nullptr);  // none declared: none in flash
  const char compiled[] = {kF32, 1, kU8, 1, kVoid};  // "x:f32,ok:u8", two bytes a field
  EXPECT_EQ(std::string(ps.type.layout, sizeof(compiled)), std::string(compiled, sizeof(compiled)));
  const ChannelInfo& lamp = bench.channels[2];
  ASSERT_NE(lamp.call, nullptr);
  EXPECT_EQ(*(void (*const*)(bool))lamp.call, &setLamp);
  EXPECT_EQ(bench.channels[3].data, &press.id);
}

// Lists for the checks (report.h), at namespace scope: the checks take their address.
constexpr auto twice = declared("d", expose("level", level), expose("level", level));
constexpr auto fine = declared("d", expose("level", level), event("press", press));
constexpr auto wrong = declared("d", expose("level", level), event("press", press), expose("bad", level).range(2, 1));

TEST(Tables, NameAndTextChecks) {
  EXPECT_TRUE(validName("speed_2"));
  EXPECT_TRUE(validName("_x"));
  EXPECT_FALSE(validName("2speed"));
  EXPECT_FALSE(validName("a-b"));
  EXPECT_FALSE(validName(""));
  EXPECT_TRUE(validName("abcdefghijklmnopqrstuvwxyz012345"));    // 32
  EXPECT_FALSE(validName("abcdefghijklmnopqrstuvwxyz0123456"));  // 33
  EXPECT_TRUE(shortText(nullptr));
  EXPECT_TRUE(shortText(std::string(255, 'a').c_str()));
  EXPECT_FALSE(shortText(std::string(256, 'a').c_str()));
  EXPECT_EQ(firstRepeated(twice.list), 0u);  // the first of the two is reported
  EXPECT_FALSE((NamesUnique<decltype(twice), &twice>::value));
  EXPECT_EQ(firstRepeated(fine.list), 2u);  // none: the list's size
  EXPECT_TRUE((NamesUnique<decltype(fine), &fine>::value));
  EXPECT_EQ((FirstMistake<decltype(fine), &fine>::value), 2u);
  EXPECT_EQ((FirstMistake<decltype(wrong), &wrong>::value), 2u);
  EXPECT_TRUE((Report<decltype(fine), &fine, false>::ok));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

namespace {

char label[8];
uint8_t beepsLeft;
uint8_t beep(uint8_t n) { return beepsLeft = n; }

}  // namespace

HUBWIRE_CHANNELS(others, "others", expose("label", label).streamable(), action("beep", beep));

namespace {
hubwire::List<int16_t, 4> shortList;         // 9 bytes: one frame
uint8_t justFits[HUBWIRE_MAX_PAYLOAD - 2];  // a sample of it: exactly one frame
uint8_t oneMore[HUBWIRE_MAX_PAYLOAD - 1];   // a sample of it does not fit: fragments
uint8_t wide[HUBWIRE_MAX_PAYLOAD + 1];      // a write of it does not fit either
uint8_t fourteen[14];                       // a sample of it is 16 bytes: what every hub accepts
uint8_t fifteen[15];                        // ... and one more
}  // namespace

HUBWIRE_CHANNELS(lists, "lists", expose("l", shortList).writable(), expose("fits", justFits));
// (A program holds one table with large values, as one with hub channels: this one is not a table.)
constexpr auto sampled = hubwire::declare::declared("sampled", hubwire::declare::expose("s", oneMore).writable());
HUBWIRE_CHANNELS(written, "written", expose("w", wide).writable(), expose("l", shortList));

namespace {

// Large values: the `large` feature when a message carrying a value (a sample: 2 bytes more) may
// not fit the device's frame; the reassembly buffer only for writes that do not fit.
TEST(Tables, ListsAndLargeValues) {
  EXPECT_EQ(hubwire_channels_lists::features, kUsesLists | kUsesWrites | kUsesReads | kUsesWide);
  EXPECT_EQ(hubwire_channels_lists::largeIn, 0);
  EXPECT_EQ(featuresOf(sampled.list) & kUsesLarge, kUsesLarge);
  EXPECT_EQ(largeInOf(sampled.list), 0);  // its write fits one frame
  EXPECT_EQ(hubwire_channels_written::features & (kUsesLarge | kUsesLists), kUsesLarge | kUsesLists);
  EXPECT_EQ(hubwire_channels_written::largeIn, sizeof(wide));
}

// Only a value whose answer or sample may pass the 16 bytes every hub accepts is checked against
// the hub's own limit (kUsesWide).
TEST(Tables, WideValues) {
  EXPECT_EQ(featuresOf(declared("a", expose("a", fourteen)).list) & kUsesWide, 0);
  EXPECT_EQ(featuresOf(declared("b", expose("b", fifteen)).list) & kUsesWide, kUsesWide);
  EXPECT_EQ(featuresOf(declared("c", expose("c", level)).list) & kUsesWide, 0);
}

// What each declaration adds to the features HUBWIRE_CHANNELS works out (features.h).
TEST(Tables, FeaturesOfTheDeclarations) {
  EXPECT_EQ(hubwire_channels_bench::features,
            kUsesWrites | kUsesReads | kUsesRanges | kUsesFailsafes | kUsesStructs | kUsesCalls | kUsesEvents);
  EXPECT_EQ(hubwire_channels_others::features, kUsesStrings | kUsesReads | kUsesStreams | kUsesCalls | kUsesReturns);
  EXPECT_EQ(featuresOf(declared("c", control("c", setLamp).failsafe(false)).list),
            kUsesCalls | kUsesFailsafes | kUsesControlFailsafes);
  EXPECT_EQ(featuresOf(declared("v", expose("v", level).writable().failsafe(1)).list),
            kUsesWrites | kUsesReads | kUsesFailsafes);
  // This program has several tables (HUBWIRE_ALL_FEATURES): the library's default holds.
  EXPECT_EQ(sketchFeatures, kAllFeatures);
  // ... and no table of the sketch's own: the session reads the one begin() was given.
  EXPECT_EQ(sketchTable.count, 0);
  EXPECT_EQ(sketchTableAt, nullptr);
}

}  // namespace
