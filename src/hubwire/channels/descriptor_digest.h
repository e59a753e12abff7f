// The descriptor's parts (descriptor_text.h) as one message for its SHA-256 digest (sha256.h), and
// what is stored in flash: hello's fixed fields, the digest, then the JSON.
#ifndef HUBWIRE_CHANNELS_DESCRIPTOR_DIGEST_H
#define HUBWIRE_CHANNELS_DESCRIPTOR_DIGEST_H

#include <stddef.h>
#include <stdint.h>

#include "../wire/messages.h"
#include "../wire/sha256.h"
#include "constexpr_text.h"
#include "descriptor_text.h"

namespace hubwire {
namespace declare {

// ---- the descriptor as one message for sha256.h: the parts joined as a balanced tree, so that
// reading a word goes log2(parts) levels deep, one call a level (each call costs GCC 5 memory) ----
#if HUBWIRE_CX_REMEMBERS
#define HUBWIRE_PART_CHAR(P, i) ((uint32_t)(uint8_t)P::at(i))
#else
#define HUBWIRE_PART_CHAR(P, i) ((uint32_t)(uint8_t)PartConst<P>::value.c[i])
#endif
// A block's words (sha256.h): word(i), word(i + 4), ... as pairs.
#define HUBWIRE_PAIR_AT(k) ((uint64_t)word(i + 8 * k) << 32 | word(i + 8 * k + 4))
#define HUBWIRE_BLOCK_OF_WORDS                                                                          \
  sha256::detail::Block{{HUBWIRE_PAIR_AT(0), HUBWIRE_PAIR_AT(1), HUBWIRE_PAIR_AT(2), HUBWIRE_PAIR_AT(3), \
                         HUBWIRE_PAIR_AT(4), HUBWIRE_PAIR_AT(5), HUBWIRE_PAIR_AT(6), HUBWIRE_PAIR_AT(7)}}
template <typename P>
struct PartMessage {
  static constexpr size_t length() { return sizeof(Chars<P>); }  // a constant: clang would work out P::length() anew
  static constexpr char at(size_t i) { return (char)HUBWIRE_PART_CHAR(P, i); }
  static constexpr uint32_t word(size_t i) {
    return HUBWIRE_PART_CHAR(P, i) << 24 | HUBWIRE_PART_CHAR(P, i + 1) << 16 | HUBWIRE_PART_CHAR(P, i + 2) << 8 |
           HUBWIRE_PART_CHAR(P, i + 3);
  }
#if HUBWIRE_CX_REMEMBERS
  static constexpr sha256::detail::Block block(size_t i) { return HUBWIRE_BLOCK_OF_WORDS; }
#endif
};
#undef HUBWIRE_PART_CHAR
template <typename D, const D* Decls, size_t Lo, size_t Hi, bool One = Hi - Lo == 1>
struct Parts {
  typedef Parts<D, Decls, Lo, (Lo + Hi) / 2> A;
  typedef Parts<D, Decls, (Lo + Hi) / 2, Hi> B;
  static constexpr size_t length() { return A::length() + B::length(); }
  static constexpr char at(size_t i) { return i < A::length() ? A::at(i) : B::at(i - A::length()); }
  static constexpr uint32_t word(size_t i) {  // a word across two parts: its bytes one by one
    return i + 4 <= A::length() ? A::word(i)
         : i >= A::length()     ? B::word(i - A::length())
                                : (uint32_t)(uint8_t)at(i) << 24 | (uint32_t)(uint8_t)at(i + 1) << 16 |
                                      (uint32_t)(uint8_t)at(i + 2) << 8 | (uint8_t)at(i + 3);
  }
#if HUBWIRE_CX_REMEMBERS  // (g++ 12 pays more for the blocks than for the words)
  static constexpr sha256::detail::Block block(size_t i) {  // one descent a block where it lies in one half
    return i + 64 <= A::length() ? A::block(i) : i >= A::length() ? B::block(i - A::length()) : across(i);
  }
  // A block across the halves, apart: avr-g++ 5.4 paid for its sixteen words at every level of
  // every block's descent, where they are not read.
  static constexpr sha256::detail::Block across(size_t i) { return HUBWIRE_BLOCK_OF_WORDS; }
#endif
};
#undef HUBWIRE_PAIR_AT
#undef HUBWIRE_BLOCK_OF_WORDS
template <typename D, const D* Decls, size_t Lo, size_t Hi>
struct Parts<D, Decls, Lo, Hi, true> : PartMessage<typename PartAt<D, Decls, Lo>::Type> {};
template <typename D, const D* Decls>
struct DescriptorMessage : Parts<D, Decls, 0, builtParts<D, Decls>()> {};

// Hello's fixed fields (bytes 6..15: the payload the device accepts, its heartbeat interval, the
// descriptor's hash and length, little-endian), then the first kDigestSize bytes of the JSON's
// SHA-256 (hello 16..31), then the JSON: hello copies its fixed part from flash in one piece,
// found at json - kDigestSize - kHelloFixed.
struct HelloFixed {
  uint8_t bytes[kHelloFixed];
};
constexpr HelloFixed helloFixed(uint16_t length, uint32_t hash) {
  return HelloFixed{{(uint8_t)HUBWIRE_MAX_PAYLOAD, (uint8_t)(HUBWIRE_MAX_PAYLOAD >> 8), (uint8_t)HUBWIRE_HEARTBEAT_MS,
                     (uint8_t)(HUBWIRE_HEARTBEAT_MS >> 8), (uint8_t)hash, (uint8_t)(hash >> 8), (uint8_t)(hash >> 16),
                     (uint8_t)(hash >> 24), (uint8_t)length, (uint8_t)(length >> 8)}};
}
template <typename D, const D* Decls>
struct JsonAndDigest {
  HelloFixed hello;
  sha256::Digest<kDigestSize> digest;
  JsonText<D, Decls> text;
};
// value is constexpr where it is declared, so it is a member of a class of its own: a class cannot
// hold a constexpr object of its own, still incomplete, type.
template <typename D, const D* Decls>
struct Json {
  typedef JsonAndDigest<D, Decls> Stored;
  static constexpr Stored value = {helloFixed((uint16_t)sizeof(JsonText<D, Decls>), hashOfText<D, Decls>()),
                                   sha256::digest<DescriptorMessage<D, Decls>, kDigestSize>(),
                                   TextConst<D, Decls>::value};
};
template <typename D, const D* Decls>
constexpr typename Json<D, Decls>::Stored Json<D, Decls>::value;

}  // namespace declare
}  // namespace hubwire

#endif
