// SHA-256 (FIPS 180-4) worked out by the compiler (C++11 constexpr): the digest of a text known
// while compiling, such as the descriptor JSON. Nothing here runs on the board: only the digest
// bytes a program stores (e.g. a Digest<16> in flash) take any room.
//
//   struct Msg {  // the message: its length and its bytes, both constexpr
//     static constexpr size_t length() { return 3; }
//     static constexpr char at(size_t i) { return "abc"[i]; }
//   };
//   const hubwire::sha256::Digest<16> id HUBWIRE_FLASH = hubwire::sha256::digest<Msg, 16>();
//
// digest<Msg, N>() is the first N bytes of SHA-256 (N = 32: all of it). The compiler's limits are
// far away for messages of up to 16 KiB (the largest descriptor): the state after each 64-byte block
// is a constant of its own (State<Msg, k>::value), so no single constant evaluation covers more than
// one block (64 rounds deep), and the chain of blocks is one template instantiation a block (257 for
// 16 KiB, under the 900 of GCC and the 1024 of clang: GCC 5.4 stops at about 56 KB). What it costs
// the compiler: bench/sha256-compile.sh (avr-g++ 5.4 keeps about 0.7 MB a block until the end).
#ifndef HUBWIRE_WIRE_SHA256_H
#define HUBWIRE_WIRE_SHA256_H

#include <stddef.h>
#include <stdint.h>

namespace hubwire {
namespace sha256 {

// The first N bytes of a digest (big-endian words, as SHA-256 prints).
template <size_t N>
struct Digest {
  uint8_t bytes[N];
};

namespace detail {

// The big-endian word of bytes i..i+3 of a message: Msg::word(i) where the message has it (Concat:
// one descent of the tree a word, not one a byte), else four at().
template <typename Msg>
constexpr uint32_t bytesWord(size_t i) {
  return (uint32_t)(uint8_t)Msg::at(i) << 24 | (uint32_t)(uint8_t)Msg::at(i + 1) << 16 |
         (uint32_t)(uint8_t)Msg::at(i + 2) << 8 | (uint8_t)Msg::at(i + 3);
}
template <typename Msg, typename = void>
struct WordOf {
  static constexpr uint32_t at(size_t i) { return bytesWord<Msg>(i); }
};
template <typename Msg>
struct WordOf<Msg, decltype((void)Msg::word(0))> {
  static constexpr uint32_t at(size_t i) { return Msg::word(i); }
};

}  // namespace detail

// Two messages one after the other (e.g. the parts of the descriptor): a message itself.
template <typename A, typename B>
struct Concat {
  static constexpr size_t length() { return A::length() + B::length(); }
  static constexpr char at(size_t i) { return i < A::length() ? A::at(i) : B::at(i - A::length()); }
  static constexpr uint32_t word(size_t i) {
    return i + 4 <= A::length() ? detail::WordOf<A>::at(i)
         : i >= A::length()     ? detail::WordOf<B>::at(i - A::length())
                                : detail::bytesWord<Concat>(i);
  }
};

namespace detail {

// Words are spelt uint32_t and constants UL throughout: on AVR an int has 16 bits.
struct Words {
  uint32_t h[8];
};
// A block's sixteen message words, two to a 64-bit element (the first in the high half).
struct Block {
  uint64_t p[8];
};

// The round constants, as a chain of conditionals: GCC 5 copied a constexpr array whole at every
// read of one element (2 KB a round).
constexpr uint32_t roundConstant(unsigned t) {
  return t == 0 ? 0x428a2f98UL : t == 1 ? 0x71374491UL : t == 2 ? 0xb5c0fbcfUL : t == 3 ? 0xe9b5dba5UL :
         t == 4 ? 0x3956c25bUL : t == 5 ? 0x59f111f1UL : t == 6 ? 0x923f82a4UL : t == 7 ? 0xab1c5ed5UL :
         t == 8 ? 0xd807aa98UL : t == 9 ? 0x12835b01UL : t == 10 ? 0x243185beUL : t == 11 ? 0x550c7dc3UL :
         t == 12 ? 0x72be5d74UL : t == 13 ? 0x80deb1feUL : t == 14 ? 0x9bdc06a7UL : t == 15 ? 0xc19bf174UL :
         t == 16 ? 0xe49b69c1UL : t == 17 ? 0xefbe4786UL : t == 18 ? 0x0fc19dc6UL : t == 19 ? 0x240ca1ccUL :
         t == 20 ? 0x2de92c6fUL : t == 21 ? 0x4a7484aaUL : t == 22 ? 0x5cb0a9dcUL : t == 23 ? 0x76f988daUL :
         t == 24 ? 0x983e5152UL : t == 25 ? 0xa831c66dUL : t == 26 ? 0xb00327c8UL : t == 27 ? 0xbf597fc7UL :
         t == 28 ? 0xc6e00bf3UL : t == 29 ? 0xd5a79147UL : t == 30 ? 0x06ca6351UL : t == 31 ? 0x14292967UL :
         t == 32 ? 0x27b70a85UL : t == 33 ? 0x2e1b2138UL : t == 34 ? 0x4d2c6dfcUL : t == 35 ? 0x53380d13UL :
         t == 36 ? 0x650a7354UL : t == 37 ? 0x766a0abbUL : t == 38 ? 0x81c2c92eUL : t == 39 ? 0x92722c85UL :
         t == 40 ? 0xa2bfe8a1UL : t == 41 ? 0xa81a664bUL : t == 42 ? 0xc24b8b70UL : t == 43 ? 0xc76c51a3UL :
         t == 44 ? 0xd192e819UL : t == 45 ? 0xd6990624UL : t == 46 ? 0xf40e3585UL : t == 47 ? 0x106aa070UL :
         t == 48 ? 0x19a4c116UL : t == 49 ? 0x1e376c08UL : t == 50 ? 0x2748774cUL : t == 51 ? 0x34b0bcb5UL :
         t == 52 ? 0x391c0cb3UL : t == 53 ? 0x4ed8aa4aUL : t == 54 ? 0x5b9cca4fUL : t == 55 ? 0x682e6ff3UL :
         t == 56 ? 0x748f82eeUL : t == 57 ? 0x78a5636fUL : t == 58 ? 0x84c87814UL : t == 59 ? 0x8cc70208UL :
         t == 60 ? 0x90befffaUL : t == 61 ? 0xa4506cebUL : t == 62 ? 0xbef9a3f7UL : 0xc67178f2UL;
}
constexpr Words initial() {
  return Words{{0x6a09e667UL, 0xbb67ae85UL, 0x3c6ef372UL, 0xa54ff53aUL, 0x510e527fUL, 0x9b05688cUL, 0x1f83d9abUL,
                0x5be0cd19UL}};
}

// Rotations spelt out, and the sigma functions written into each round rather than called: every
// constexpr call costs GCC 5 memory that it keeps until the end of the file (11 % of a block).
#define HUBWIRE_SHA_S0(x) (((x) >> 2 | (x) << 30) ^ ((x) >> 13 | (x) << 19) ^ ((x) >> 22 | (x) << 10))
#define HUBWIRE_SHA_S1(x) (((x) >> 6 | (x) << 26) ^ ((x) >> 11 | (x) << 21) ^ ((x) >> 25 | (x) << 7))
#define HUBWIRE_SHA_s0(x) (((x) >> 7 | (x) << 25) ^ ((x) >> 18 | (x) << 14) ^ (x) >> 3)
#define HUBWIRE_SHA_s1(x) (((x) >> 17 | (x) << 15) ^ ((x) >> 19 | (x) << 13) ^ (x) >> 10)

// ---- padding: the message, 0x80, zeros, then its length in bits (64-bit big-endian) ----
// size_t has 16 bits on AVR: the bit count is worked out in 64 bits.
constexpr size_t blockCount(size_t length) { return (length + 8) / 64 + 1; }
constexpr uint8_t lengthByte(size_t length, size_t fromEnd) {
  return (uint8_t)(((uint64_t)length * 8) >> (8 * fromEnd));
}
template <typename Msg>
constexpr uint8_t paddedByte(size_t i) {
  return i < Msg::length()    ? (uint8_t)Msg::at(i)
         : i == Msg::length() ? (uint8_t)0x80
         : i + 8 < blockCount(Msg::length()) * 64
             ? (uint8_t)0
             : lengthByte(Msg::length(), blockCount(Msg::length()) * 64 - 1 - i);
}
// A word of the padded message. One call a word where the message is read a word at a time (each
// constexpr call costs GCC 5 memory it keeps): Msg::word() is called from here directly.
template <typename Msg, typename = void>
struct PaddedWord {
  static constexpr uint32_t at(size_t i) {
    return i + 4 <= Msg::length() ? bytesWord<Msg>(i)
         : (uint32_t)paddedByte<Msg>(i) << 24 | (uint32_t)paddedByte<Msg>(i + 1) << 16 |
           (uint32_t)paddedByte<Msg>(i + 2) << 8 | (uint32_t)paddedByte<Msg>(i + 3);
  }
};
template <typename Msg>
struct PaddedWord<Msg, decltype((void)Msg::word(0))> {
  static constexpr uint32_t at(size_t i) {
    return i + 4 <= Msg::length() ? Msg::word(i)
         : (uint32_t)paddedByte<Msg>(i) << 24 | (uint32_t)paddedByte<Msg>(i + 1) << 16 |
           (uint32_t)paddedByte<Msg>(i + 2) << 8 | (uint32_t)paddedByte<Msg>(i + 3);
  }
};

// ---- one block: 64 rounds, one call each (64 deep), round t a function of its own with its
// constant folded in (Round<t>::K). The working variables a..h and the schedule's window W[t..t+15]
// are word parameters, not an aggregate, and T1 is written out twice rather than passed through a
// call of its own: GCC 5 keeps every constexpr call's arguments until the end of the file, so fewer
// and smaller calls are what keeps its memory down. For the same reason the window travels as pairs
// of words in 64-bit parameters (16 or 17 parameters a round, not 24): an even round takes eight
// pairs, an odd one its own word, seven pairs and the window's last word, so that every pair passes
// on unchanged and one new pair is made every other round. W[t+16] is made while round t runs. ----
#define HUBWIRE_SHA_HI(p) ((uint32_t)((p) >> 32))
#define HUBWIRE_SHA_LO(p) ((uint32_t)(p))
#define HUBWIRE_SHA_PAIR(x, y) ((uint64_t)(x) << 32 | (y))
#define HUBWIRE_SHA_T1(e, f, g, h, w) (h + HUBWIRE_SHA_S1(e) + ((e & f) ^ (~e & g)) + K + (w))
#define HUBWIRE_SHA_T2(a, b, c) (HUBWIRE_SHA_S0(a) + ((a & b) ^ (a & c) ^ (b & c)))
template <unsigned T, bool Odd = T % 2 == 1>
struct Round;
// Even rounds: the schedule's window as eight pairs of words.
template <unsigned T>
struct Round<T, false> {
  static constexpr uint32_t K = roundConstant(T);
  static constexpr Words run(uint32_t a, uint32_t b, uint32_t c, uint32_t d, uint32_t e, uint32_t f, uint32_t g,
                             uint32_t h, uint64_t p01, uint64_t p23, uint64_t p45, uint64_t p67, uint64_t p89,
                             uint64_t p1011, uint64_t p1213, uint64_t p1415) {
    return Round<T + 1>::run(HUBWIRE_SHA_T1(e, f, g, h, HUBWIRE_SHA_HI(p01)) + HUBWIRE_SHA_T2(a, b, c), a, b, c,
                             d + HUBWIRE_SHA_T1(e, f, g, h, HUBWIRE_SHA_HI(p01)), e, f, g, HUBWIRE_SHA_LO(p01), p23,
                             p45, p67, p89, p1011, p1213, p1415,
                             HUBWIRE_SHA_s1(HUBWIRE_SHA_HI(p1415)) + HUBWIRE_SHA_LO(p89) +
                                 HUBWIRE_SHA_s0(HUBWIRE_SHA_LO(p01)) + HUBWIRE_SHA_HI(p01));
  }
};
// Odd rounds: its word alone, seven pairs, and the window's last word alone.
template <unsigned T>
struct Round<T, true> {
  static constexpr uint32_t K = roundConstant(T);
  static constexpr Words run(uint32_t a, uint32_t b, uint32_t c, uint32_t d, uint32_t e, uint32_t f, uint32_t g,
                             uint32_t h, uint32_t w0, uint64_t p12, uint64_t p34, uint64_t p56, uint64_t p78,
                             uint64_t p910, uint64_t p1112, uint64_t p1314, uint32_t w15) {
    return Round<T + 1>::run(HUBWIRE_SHA_T1(e, f, g, h, w0) + HUBWIRE_SHA_T2(a, b, c), a, b, c,
                             d + HUBWIRE_SHA_T1(e, f, g, h, w0), e, f, g, p12, p34, p56, p78, p910, p1112, p1314,
                             HUBWIRE_SHA_PAIR(w15, HUBWIRE_SHA_s1(HUBWIRE_SHA_LO(p1314)) + HUBWIRE_SHA_HI(p910) +
                                                       HUBWIRE_SHA_s0(HUBWIRE_SHA_HI(p12)) + w0));
  }
};
template <unsigned T>
constexpr uint32_t Round<T, false>::K;
template <unsigned T>
constexpr uint32_t Round<T, true>::K;
template <>
struct Round<64, false> {
  static constexpr Words run(uint32_t a, uint32_t b, uint32_t c, uint32_t d, uint32_t e, uint32_t f, uint32_t g,
                             uint32_t h, uint64_t, uint64_t, uint64_t, uint64_t, uint64_t, uint64_t, uint64_t,
                             uint64_t) {
    return Words{{a, b, c, d, e, f, g, h}};
  }
};
// A block's sixteen words, in pairs: from Msg::block() where the message has it (Parts in
// descriptor_digest.h: one descent of its tree a block, not one a word) and the block holds no padding,
// else a word at a time.
#define HUBWIRE_SHA_W(i) HUBWIRE_SHA_PAIR(PaddedWord<Msg>::at(at + 8 * i), PaddedWord<Msg>::at(at + 8 * i + 4))
template <typename Msg>
constexpr Block paddedBlock(size_t at) {
  return Block{{HUBWIRE_SHA_W(0), HUBWIRE_SHA_W(1), HUBWIRE_SHA_W(2), HUBWIRE_SHA_W(3), HUBWIRE_SHA_W(4),
                HUBWIRE_SHA_W(5), HUBWIRE_SHA_W(6), HUBWIRE_SHA_W(7)}};
}
#undef HUBWIRE_SHA_W
template <typename Msg, typename = void>
struct BlockOf {
  static constexpr Block at(size_t i) { return paddedBlock<Msg>(i); }
};
template <typename Msg>
struct BlockOf<Msg, decltype((void)Msg::block(0))> {
  static constexpr Block at(size_t i) { return i + 64 <= Msg::length() ? Msg::block(i) : paddedBlock<Msg>(i); }
};
constexpr Words blockRounds(const Words& h, const Block w) {
  return Round<0>::run(h.h[0], h.h[1], h.h[2], h.h[3], h.h[4], h.h[5], h.h[6], h.h[7], w.p[0], w.p[1], w.p[2],
                       w.p[3], w.p[4], w.p[5], w.p[6], w.p[7]);
}
constexpr Words add(const Words& h, const Words& v) {
  return Words{{h.h[0] + v.h[0], h.h[1] + v.h[1], h.h[2] + v.h[2], h.h[3] + v.h[3], h.h[4] + v.h[4],
                h.h[5] + v.h[5], h.h[6] + v.h[6], h.h[7] + v.h[7]}};
}
template <typename Msg>
constexpr Words compress(const Words& h, size_t block) {
  return add(h, blockRounds(h, BlockOf<Msg>::at(block * 64)));
}

// The state after the first K blocks: each a constant of its own, evaluated once. Defined below as
// well, for a digest() called where no constant is required (at -O0 clang then reads the last state
// from memory; the rounds still never run on the target).
template <typename Msg, size_t K>
struct State {
  static constexpr Words value = compress<Msg>(State<Msg, K - 1>::value, K - 1);
};
template <typename Msg>
struct State<Msg, 0> {
  static constexpr Words value = initial();
};
template <typename Msg, size_t K>
constexpr Words State<Msg, K>::value;
template <typename Msg>
constexpr Words State<Msg, 0>::value;

// 0, 1, ..., N-1 (N at most 32: a linear build is shallow enough).
template <size_t... I>
struct Indices {};
template <size_t N, size_t... I>
struct MakeIndices : MakeIndices<N - 1, N - 1, I...> {};
template <size_t... I>
struct MakeIndices<0, I...> {
  typedef Indices<I...> type;
};

template <size_t... I>
constexpr Digest<sizeof...(I)> bytesOf(const Words& h, Indices<I...>) {
  return Digest<sizeof...(I)>{{(uint8_t)(h.h[I / 4] >> (24 - 8 * (I % 4)))...}};
}

}  // namespace detail

// The first N bytes of SHA-256 of Msg (a type with static constexpr length() and at(i)).
template <typename Msg, size_t N = 32>
constexpr Digest<N> digest() {
  static_assert(N >= 1 && N <= 32, "a SHA-256 digest has 1..32 bytes");
  return detail::bytesOf(detail::State<Msg, detail::blockCount(Msg::length())>::value,
                         typename detail::MakeIndices<N>::type());
}

}  // namespace sha256
}  // namespace hubwire

#undef HUBWIRE_SHA_S0
#undef HUBWIRE_SHA_S1
#undef HUBWIRE_SHA_s0
#undef HUBWIRE_SHA_s1
#undef HUBWIRE_SHA_HI
#undef HUBWIRE_SHA_LO
#undef HUBWIRE_SHA_PAIR
#undef HUBWIRE_SHA_T1
#undef HUBWIRE_SHA_T2

#endif
