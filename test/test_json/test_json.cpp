// The compile-time JSON writer (channels/json.h): each kind of piece, its length and characters.
#include <gtest/gtest.h>

#include <string>

#include "hubwire/channels/channel.h"
#include "hubwire/channels/json.h"

using namespace hubwire;
using namespace hubwire::declare;

namespace {

std::string text(const Piece& p) {
  std::string s;
  for (size_t i = 0; i < pieceLength(p); ++i) s += pieceAt(p, i);
  return s;
}

TEST(Json, LiteralsAndIntegers) {
  EXPECT_EQ(text(literal("]}")), "]}");
  EXPECT_EQ(text(empty()), "");
  EXPECT_EQ(text(integer(",\"id\":", 12)), ",\"id\":12");
  EXPECT_EQ(text(integer("", 0)), "0");
  EXPECT_EQ(text(integer("", -40)), "-40");
  EXPECT_EQ(text(number("", (uint32_t)4294967295u)), "4294967295");
  EXPECT_EQ(text(number("", (int8_t)-128)), "-128");
  static_assert(pieceLength(integer("x", 123)) == 4, "lengths are constant expressions");
}

TEST(Json, FloatsAsTheShortestTextThatReadsBack) {
  EXPECT_EQ(text(number("", 1.0f)), "1");
  EXPECT_EQ(text(number("", -1.0f)), "-1");
  EXPECT_EQ(text(number("", 0.25f)), "0.25");
  EXPECT_EQ(std::stof(text(number("", 0.1f))), 0.1f);
  EXPECT_EQ(std::stof(text(number("", 3.5))), 3.5f);  // doubles are written as floats
}

TEST(Json, StringsAreEscaped) {
  EXPECT_EQ(text(quoted(",\"n\":\"", "speed")), ",\"n\":\"speed\"");
  EXPECT_EQ(text(quoted("\"", "a \"q\" \\ b")), R"("a \"q\" \\ b")");
}

TEST(Json, TypeNamesAccessLettersAndFields) {
  EXPECT_EQ(text(typeNamed(",\"t\":\"", kU16)), ",\"t\":\"u16\"");
  EXPECT_EQ(text(Piece{"", kAccessLetters, kReadable | kWritable | kStreamable, 0, "", ""}), "rws");
  EXPECT_EQ(text(Piece{"", kAccessLetters, kCallable, 0, "", ""}), "c");
  EXPECT_EQ(text(Piece{"", kAccessLetters, kEventAccess, 0, "", ""}), "e");
  EXPECT_EQ(text(Piece{"[", kFields, 0, 0, "x:u8,y:i16[2]", "]"}),
            R"([{"n":"x","t":"u8"},{"n":"y","t":"i16","c":2}])");
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
