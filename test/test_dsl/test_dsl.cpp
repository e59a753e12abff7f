// The declaration DSL (channels/dsl.h): what each declaration and option records, the checks it
// leaves for tables.h, and one channel's JSON.
#include <gtest/gtest.h>

#include <math.h>
#include <string.h>

#include <string>

#include "hubwire/channels/dsl.h"

using namespace hubwire;
using namespace hubwire::declare;

namespace {

float speed;
uint8_t level;
int16_t temps[2];
char label[9];
Event<uint16_t> alarm;
int calls;
void changed() { ++calls; }
void setLevel(uint8_t v) { level = v; }
bool even(uint16_t v) { return v % 2 == 0; }
int32_t twice(int16_t v) { return v * 2; }

template <typename D>
std::string json(const D& d, uint8_t id) {
  std::string s;
  for (size_t i = 0; i < d.jsonLength(id); ++i) s += d.jsonAt(id, i);
  return s;
}

TEST(Dsl, ExposeAndItsOptions) {
  constexpr auto d = expose("speed", speed).writable().streamable().range(-1.0f, 1.0f).unit("m/s").failsafe(0.0f)
                         .describe("wheel speed").onChange(changed);
  EXPECT_EQ(json(d, 1), R"({"id":1,"n":"speed","a":"rws","t":"f32","u":"m/s","min":-1,"max":1,"fs":0,"d":"wheel speed"})");
  EXPECT_EQ(json(d, 2).substr(0, 8), R"(,{"id":2)");  // later channels follow a comma
  ChannelInfo info = d.info(nullptr, nullptr, nullptr);
  EXPECT_EQ(info.data, &speed);
  EXPECT_EQ(info.access, kReadable | kWritable | kStreamable);
  EXPECT_EQ(info.flags, kHasRange | kHasFailsafe);
  EXPECT_EQ(d.call(), &changed);
  EXPECT_TRUE(d.hasLimits());
  ChannelLimits lim = d.limits();
  EXPECT_EQ((int32_t)(uint32_t)lim.min.bits, -0x3F800000);  // -1.0f's key: its magnitude's bits, negated
  EXPECT_EQ((int32_t)(uint32_t)lim.max.bits, 0x3F800000);
  EXPECT_EQ(lim.failsafe.f32, 0.0f);
  float in = 0.5f, out = 1.5f;
  EXPECT_TRUE(lim.inRange((const uint8_t*)&in, &lim.min, &lim.max));
  EXPECT_FALSE(lim.inRange((const uint8_t*)&out, &lim.min, &lim.max));
}

// A float range's limits are kept as keys the compiler works out from the floats' bits (channel.h).
int32_t keyOfBits(float v) {
  uint32_t b;
  memcpy(&b, &v, 4);
  return (b & 0x80000000u) ? -(int32_t)(b & 0x7FFFFFFFu) : (int32_t)b;
}

TEST(Dsl, FloatLimitKeysAreTheFloatsBits) {
  static_assert(f32Key(1.0f) == 0x3F800000 && f32Key(-2.5f) == -0x40200000, "worked out while compiling");
  static_assert(f32Key(-0.0f) == 0 && f32Key(INFINITY) == 0x7F800000 && f32Key(-INFINITY) == -0x7F800000, "ends");
  for (float v : {0.1f, -0.1f, 1.0f, 1.5f, 3.0f, 1e-3f, 123456.789f, -7.25e12f, 3.40282347e38f, -3.40282347e38f,
                  1.17549435e-38f, 1e-40f, -1e-45f, 0.0f, 0.99999994f, 1.0000001f})
    EXPECT_EQ(f32Key(v), keyOfBits(v)) << v;
}

TEST(Dsl, ArraysStringsAndPlainVariables) {
  EXPECT_EQ(json(expose("temps", temps).range(-40, 125), 3),
            R"(,{"id":3,"n":"temps","a":"r","t":"i16","c":2,"min":-40,"max":125})");
  EXPECT_EQ(json(expose("label", label).writable(), 1), R"({"id":1,"n":"label","a":"rw","t":"str","c":8})");
  constexpr auto plain = expose("level", level);
  EXPECT_FALSE(plain.hasLimits());
  EXPECT_EQ(plain.call(), nullptr);
  EXPECT_EQ(json(plain, 1), R"({"id":1,"n":"level","a":"r","t":"u8"})");
}

TEST(Dsl, ControlsActionsAndEvents) {
  EXPECT_EQ(json(control("level", setLevel).failsafe(0), 1), R"({"id":1,"n":"level","a":"w","t":"u8","fs":0})");
  EXPECT_EQ(json(control("even", even), 1), R"({"id":1,"n":"even","a":"w","t":"u16"})");
  EXPECT_EQ(json(action("twice", twice), 1), R"({"id":1,"n":"twice","a":"c","t":"i16","rt":"i32"})");
  EXPECT_EQ(json(action("reset", changed), 1), R"({"id":1,"n":"reset","a":"c","t":"void"})");
  EXPECT_EQ(json(event("alarm", alarm), 1), R"({"id":1,"n":"alarm","a":"e","t":"u16"})");
  // The thunk calls the function with the argument's bytes and writes the result's.
  constexpr auto a = action("twice", twice);
  ChannelInfo info = a.info(nullptr, nullptr, nullptr);
  int32_t (*fn)(int16_t) = a.call();
  int16_t arg = 21;
  int32_t ret = 0;
  ASSERT_TRUE(info.thunk(&fn, (const uint8_t*)&arg, (uint8_t*)&ret));
  EXPECT_EQ(ret, 42);
  EXPECT_EQ(event("alarm", alarm).info(nullptr, nullptr, nullptr).data, &alarm.id);
}

TEST(Dsl, ValuesThatDoNotFitAndRangesOutOfOrderAreMarked) {
  EXPECT_EQ(expose("level", level).range(0, 255).mistake(), kNoMistake);
  EXPECT_EQ(expose("level", level).range(0, 300).mistake(), kRangeValue);
  EXPECT_EQ(expose("level", level).range(-1, 200).mistake(), kRangeValue);  // not "min > max"
  EXPECT_EQ(expose("level", level).writable().failsafe(-1).mistake(), kFailsafeValue);
  EXPECT_EQ(expose("speed", speed).range(0.1, 0.2).mistake(), kNoMistake);  // a float rounds
  EXPECT_EQ(expose("level", level).range(1, 5).mistake(), kNoMistake);
  EXPECT_EQ(expose("level", level).range(5, 1).mistake(), kRangeOrder);
  EXPECT_EQ(expose("level", level).writable().range(1, 5).failsafe(6).mistake(), kFailsafeOutsideRange);
  EXPECT_EQ(expose("level", level).writable().failsafe(0).range(1, 5).mistake(), kFailsafeOutsideRange);
  EXPECT_EQ(expose("level", level).writable().failsafe(5).range(1, 5).mistake(), kNoMistake);
  EXPECT_EQ(expose("2level", level).mistake(), kBadName);
  // The first mistake is the one reported.
  EXPECT_EQ(expose("level", level).range(5, 1).failsafe(300).mistake(), kRangeOrder);
}

// On the Uno an int has 16 bits: (int)(uint16_t)-1 == -1 there, so the sign is compared too.
TEST(Dsl, ANegativeValueNeverFitsAnUnsignedType) {
  EXPECT_FALSE(Limits<uint16_t>::fits((int16_t)-1));
  EXPECT_FALSE(Limits<uint32_t>::fits((int32_t)-1));
  EXPECT_FALSE(Limits<int16_t>::fits((uint16_t)40000));
  EXPECT_TRUE(Limits<uint16_t>::fits((int16_t)5));
  EXPECT_TRUE(Limits<int16_t>::fits((uint16_t)5));
}

TEST(Dsl, WhetherAFunctionIsCalledIsKnownFromTheDeclaration) {
  EXPECT_FALSE(expose("level", level).writable().hasCall());
  EXPECT_TRUE(expose("level", level).writable().onChange(changed).hasCall());
  EXPECT_TRUE(control("level", setLevel).hasCall());
  EXPECT_TRUE(action("twice", twice).hasCall());
  EXPECT_FALSE(event("alarm", alarm).hasCall());
  // The marker stays out of the record the session reads.
  EXPECT_EQ(expose("level", level).onChange(changed).info(nullptr, nullptr, nullptr).flags, 0);
}

TEST(Dsl, DeviceNameAndTheList) {
  constexpr DeviceName dev = device("rover").firmware("1.0.0");
  EXPECT_STREQ(dev.name, "rover");
  EXPECT_STREQ(dev.firmwareText, "1.0.0");
  EXPECT_EQ(DeviceName("bare").firmwareText, nullptr);
  constexpr auto l = declared("rover", expose("level", level), event("alarm", alarm));
  EXPECT_EQ(decltype(l)::size(), 2);
  EXPECT_STREQ(l.list.head.name(), "level");
  EXPECT_STREQ(l.list.tail.head.name(), "alarm");
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
