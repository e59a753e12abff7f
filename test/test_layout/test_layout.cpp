// The struct-layout parser (channels/layout.h): sizes with the board's alignment, malformed texts,
// and the descriptor's "f" list a layout stands for.
#include <gtest/gtest.h>

#include <string>

#include "hubwire/channels/layout.h"

using namespace hubwire;
using namespace hubwire::declare;

namespace {

std::string fieldsJson(const char* layout) {
  std::string s;
  for (size_t i = 0; i < fieldsLength(layout); ++i) s += fieldsAt(layout, i);
  return s;
}

struct Imu {
  float ax;
  int16_t gyro[3];
};
struct Padded {
  uint8_t a;
  uint32_t b;
  uint8_t c;
};
struct Mixed {
  bool on;
  uint16_t n;
  int8_t k[3];
  double d;
};

TEST(Layout, SizeMatchesTheStructWithItsAlignment) {
  EXPECT_EQ(layoutSize("ax:f32,gyro:i16[3]"), sizeof(Imu));
  EXPECT_EQ(layoutSize("a:u8,b:u32,c:u8"), sizeof(Padded));
  EXPECT_EQ(layoutSize("on:bool,n:u16,k:i8[3],d:f64"), sizeof(Mixed));
  EXPECT_EQ(layoutSize("x:u8"), 1u);
  EXPECT_EQ(layoutSize("x:u8[255]"), 255u);
  static_assert(layoutSize("ax:f32,gyro:i16[3]") == sizeof(Imu), "worked out while compiling");
}

std::string compiled(const char* layout) {
  std::string s;
  for (size_t i = 0; i < compiledLayoutLength(layout); ++i) s += (char)compiledLayoutAt(layout, i);
  return s;
}

// What the board's struct codec reads: type code and element count a field, then kVoid.
TEST(Layout, CompiledFormHasTypeAndCountPerField) {
  EXPECT_EQ(compiled("ax:f32,gyro:i16[3]"), std::string({(char)kF32, 1, (char)kI16, 3, (char)kVoid}));
  EXPECT_EQ(compiled("x:u8"), std::string({(char)kU8, 1, (char)kVoid}));
  EXPECT_EQ(compiled("on:bool,n:u16,k:i8[255],d:f64"),
            std::string({(char)kBool, 1, (char)kU16, 1, (char)kI8, (char)255, (char)kF64, 1, (char)kVoid}));
  static_assert(compiledLayoutAt("a:u8,b:f64[2]", 3) == 2, "worked out while compiling");
}

TEST(Layout, MalformedTextsHaveNoSize) {
  const char* bad[] = {"",         "a",        "a:",       ":u8",        "a:u9",       "a:u8[",
                       "a:u8[0]",  "a:u8[256]", "a:u8[3",  "a:u8,",      "a:u8,,b:u8", "a:u8]",
                       "a:u8 ",    "a:f32x",   "a:str",    "a:struct"};
  for (const char* s : bad) EXPECT_EQ(layoutSize(s), kBadLayout) << s;
}

TEST(Layout, FieldsBecomeTheDescriptorsList) {
  EXPECT_EQ(fieldsJson("ax:f32,gyro:i16[3]"), R"({"n":"ax","t":"f32"},{"n":"gyro","t":"i16","c":3})");
  EXPECT_EQ(fieldsJson("x:u8"), R"({"n":"x","t":"u8"})");
  EXPECT_EQ(fieldsJson("k:i8[2],on:bool"), R"({"n":"k","t":"i8","c":2},{"n":"on","t":"bool"})");
}

TEST(Layout, TypeNamesAndSizes) {
  EXPECT_STREQ(typeNameOf(kBool), "bool");
  EXPECT_STREQ(typeNameOf(kI16), "i16");
  EXPECT_STREQ(typeNameOf(kF64), "f64");
  EXPECT_STREQ(typeNameOf(kStr), "str");
  EXPECT_STREQ(typeNameOf(kStruct), "struct");
  EXPECT_STREQ(typeNameOf(kVoid), "void");
  EXPECT_EQ(scalarBytes(kU8), 1u);
  EXPECT_EQ(scalarBytes(kI16), 2u);
  EXPECT_EQ(scalarBytes(kF32), 4u);
  EXPECT_EQ(scalarBytes(kF64), 8u);
  EXPECT_EQ(scalarBytes(kStr), 0u);
  EXPECT_EQ(layoutTypeAt("u32,", 0), kU32);
  EXPECT_EQ(layoutTypeAt("u3", 0), kVoid);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
