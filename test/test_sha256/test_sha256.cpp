// SHA-256 worked out by the compiler (wire/sha256.h) against known digests: the NIST examples
// (FIPS 180-2 appendix B, "abc" and the 448- and 896-bit messages), the empty message, the lengths
// where padding changes (55, 56, 63, 64, 65 bytes), a 16 KiB message (the largest descriptor) and
// one with every byte value. The expected values are Python's hashlib.sha256(...).hexdigest() of
// the same bytes (the generator of each message is written out beside it in Python).
#include <gtest/gtest.h>

#include <string>

#include "hubwire/wire/sha256.h"

using namespace hubwire;

namespace {

constexpr size_t textLength(const char* s, size_t n = 0) { return s[n] ? textLength(s, n + 1) : n; }

// A message from a string literal: T::text() returns it.
template <typename T>
struct Literal {
  static constexpr size_t length() { return textLength(T::text()); }
  static constexpr char at(size_t i) { return T::text()[i]; }
};
struct EmptyText {
  static constexpr const char* text() { return ""; }
};
struct AbcText {
  static constexpr const char* text() { return "abc"; }
};
struct Nist448Text {
  static constexpr const char* text() { return "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"; }
};
struct Nist896Text {
  static constexpr const char* text() {
    return "abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmnhijklmnoijklmnopjklmnopqklmnopqrlmnopqrsmnopqrstnopqrstu";
  }
};
typedef Literal<EmptyText> Empty;
typedef Literal<AbcText> Abc;
typedef Literal<Nist448Text> Nist448;
typedef Literal<Nist896Text> Nist896;

// bytes(ord('a') + i % 26 for i in range(N))
template <size_t N>
struct Alphabet {
  static constexpr size_t length() { return N; }
  static constexpr char at(size_t i) { return (char)('a' + i % 26); }
};

// a = 'abcdefghijklmnopqrstuvwxyz0123456789'; bytes(ord(a[(i % 36 * 7 + i // 64) % 36]) for i in range(16384))
struct Large {
  static constexpr size_t length() { return 16384; }
  static constexpr char at(size_t i) { return "abcdefghijklmnopqrstuvwxyz0123456789"[(i % 36 * 7 + i / 64) % 36]; }
};

// bytes((i % 256 * 131 + i // 256) % 256 for i in range(1000)): bytes from 0x80 up, which a char
// holds as negative numbers where char is signed.
struct AllBytes {
  static constexpr size_t length() { return 1000; }
  static constexpr char at(size_t i) { return (char)(uint8_t)((i % 256 * 131 + i / 256) % 256); }
};

template <size_t N>
std::string hex(const sha256::Digest<N>& d) {
  static const char digits[] = "0123456789abcdef";
  std::string s;
  for (size_t i = 0; i < N; ++i) {
    s += digits[d.bytes[i] >> 4];
    s += digits[d.bytes[i] & 15];
  }
  return s;
}

// The compile-time property itself: these digests are constants the compiler checks.
constexpr sha256::Digest<32> kAbc = sha256::digest<Abc>();
static_assert(kAbc.bytes[0] == 0xba && kAbc.bytes[1] == 0x78 && kAbc.bytes[30] == 0x15 && kAbc.bytes[31] == 0xad,
              "SHA-256(\"abc\") = ba7816bf...f20015ad");
constexpr sha256::Digest<32> kEmpty = sha256::digest<Empty>();
static_assert(kEmpty.bytes[0] == 0xe3 && kEmpty.bytes[1] == 0xb0 && kEmpty.bytes[31] == 0x55,
              "SHA-256(\"\") = e3b0c442...7852b855");
constexpr sha256::Digest<16> kPad56 = sha256::digest<Alphabet<56>, 16>();
static_assert(sizeof(kPad56) == 16 && kPad56.bytes[0] == 0x78 && kPad56.bytes[15] == 0x1d,
              "first 16 bytes of SHA-256 of 56 bytes (the length spills into a second block)");
constexpr sha256::Digest<16> kLarge = sha256::digest<Large, 16>();
static_assert(kLarge.bytes[0] == 0xbc && kLarge.bytes[15] == 0x5d, "first 16 bytes of SHA-256 of 16 KiB");

TEST(Sha256, NistExamples) {
  EXPECT_EQ(hex(sha256::digest<Empty>()), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(hex(sha256::digest<Abc>()), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(hex(sha256::digest<Nist448>()), "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(hex(sha256::digest<Nist896>()), "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1");
}

TEST(Sha256, PaddingEdges) {
  // 55 bytes: 0x80 and the length fill one block; 56: the length goes to a second block; 63, 64,
  // 65: the 0x80 at the end of the first block, at the start of the second, inside it.
  EXPECT_EQ(hex(sha256::digest<Alphabet<55> >()), "595615dbe4f0f407ae397d08b4c2cb870cb9b0e11937416f950c5160acf9c005");
  EXPECT_EQ(hex(sha256::digest<Alphabet<56> >()), "784f623b787495078e93ff28a25b581df0584055a7e71d8cd90c454716b92f51");
  EXPECT_EQ(hex(sha256::digest<Alphabet<63> >()), "5ca3e1ef5207490eac01a795e5cc94d59582a5118bf9534665c8668d87aa647c");
  EXPECT_EQ(hex(sha256::digest<Alphabet<64> >()), "2fcd5a0d60e4c941381fcc4e00a4bf8be422c3ddfafb93c809e8d1e2bfffae8e");
  EXPECT_EQ(hex(sha256::digest<Alphabet<65> >()), "1b3cd1877ab2f2f19f7be001722554f336cb799df0329de0bb4c118dc6abc06d");
  // The same edges one block further on.
  EXPECT_EQ(hex(sha256::digest<Alphabet<119> >()), "faef67da856d6fd9c8d12f9ed0a4fefd3cf0ce085ab43e2907418d457e3c354b");
  EXPECT_EQ(hex(sha256::digest<Alphabet<120> >()), "c9512b08619c19fbb503c7da6b46ef20301e5f7a7a5f43989182398536f5c5c8");
}

TEST(Sha256, SixteenKibibytes) {
  EXPECT_EQ(hex(sha256::digest<Large>()), "bc9cfb6e247244da4ba961c84393a85d7d2842c80078739e5b4cbf1f0923b6a8");
}

TEST(Sha256, BytesAbove0x7fAreTakenUnsigned) {
  EXPECT_EQ(hex(sha256::digest<AllBytes>()), "ce4866fe66ae964af5e434c0b2b1bcaa5f122adc7089cf66a7c2a69c69545d9f");
}

TEST(Sha256, ShortDigestIsThePrefix) {
  EXPECT_EQ(hex(sha256::digest<Large, 16>()), "bc9cfb6e247244da4ba961c84393a85d");
  EXPECT_EQ(hex(sha256::digest<Abc, 1>()), "ba");
  EXPECT_EQ(sizeof(sha256::Digest<16>), 16u);
}

TEST(Sha256, ConcatenatedPartsHashAsOneMessage) {
  // hashlib.sha256(b"abc" + b"abcdbcdecdefdefg...nopq"): the parts meet inside the first block.
  typedef sha256::Concat<Abc, Nist448> Joined;
  EXPECT_EQ(Joined::length(), 59u);
  EXPECT_EQ(hex(sha256::digest<Joined>()), "ae1dc6dfaa79812eb3f4d2b7aea02ed0deb3e886647bb2f3482819ca53c8cb9d");
  // Split anywhere, the digest is that of the whole: both are the 64 bytes of Alphabet<64>.
  EXPECT_EQ(hex(sha256::digest<sha256::Concat<Alphabet<26>, Alphabet<38> > >()),
            "2fcd5a0d60e4c941381fcc4e00a4bf8be422c3ddfafb93c809e8d1e2bfffae8e");
  EXPECT_EQ(hex(sha256::digest<sha256::Concat<Alphabet<52>, Alphabet<12> > >()),
            "2fcd5a0d60e4c941381fcc4e00a4bf8be422c3ddfafb93c809e8d1e2bfffae8e");
  EXPECT_EQ(hex(sha256::digest<sha256::Concat<Empty, Nist896> >()), hex(sha256::digest<Nist896>()));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
