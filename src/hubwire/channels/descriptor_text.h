// The descriptor JSON of a declaration list as the compiler builds it: one char array per part (the
// head, each channel's entry, the hub list's head and entries, the tail) laid end to end in flash,
// with its FNV-1a hash (hello carries it) and SHA-256 digest (hello's descriptor id).
//
// What it costs the compiler grows with the descriptor's length, no faster (bench/DESCRIPTOR-COMPILE.md):
// every character is worked out once, by a few constexpr calls. Where calls are remembered (GCC 5,
// constexpr_text.h) both hashes read those same calls again, never the arrays: GCC 5 copies a
// constant array whole at each read of one element, which made reading the JSON back quadratic.
// Elsewhere they read the arrays. steps.h has the compiler work it out in steps; the digest's message
// and the constant stored in flash are in descriptor_digest.h.
#ifndef HUBWIRE_CHANNELS_DESCRIPTOR_TEXT_H
#define HUBWIRE_CHANNELS_DESCRIPTOR_TEXT_H

#include <stddef.h>
#include <stdint.h>

#include "../wire/messages.h"
#include "../wire/sha256.h"
#include "constexpr_text.h"
#include "dsl.h"

namespace hubwire {
namespace declare {

// The list from declaration I on, as a pointer into the sketch's constant: one step from the
// previous one, so that reaching every declaration costs n steps, not n^2 (a walk from the
// start for each, which for 254 channels was 32,000 function templates).
template <typename D, const D* Decls, size_t I>
struct ListAt {
  typedef decltype(ListAt<D, Decls, I - 1>::ptr->tail) Type;
  static constexpr const Type* ptr = &ListAt<D, Decls, I - 1>::ptr->tail;
};
template <typename D, const D* Decls>
struct ListAt<D, Decls, 0> {
  typedef decltype(Decls->list) Type;
  static constexpr const Type* ptr = &Decls->list;
};
template <typename D, const D* Decls, size_t I>
constexpr const typename ListAt<D, Decls, I>::Type* ListAt<D, Decls, I>::ptr;
template <typename D, const D* Decls>
constexpr const typename ListAt<D, Decls, 0>::Type* ListAt<D, Decls, 0>::ptr;

// The I-th declaration (0-based) of a sketch's list, as a constant of its own.
template <typename D, const D* Decls, size_t I>
struct DeclAt {
  typedef decltype(ListAt<D, Decls, I>::ptr->head) Type;
  static constexpr Type decl = ListAt<D, Decls, I>::ptr->head;
};
template <typename D, const D* Decls, size_t I>
constexpr typename DeclAt<D, Decls, I>::Type DeclAt<D, Decls, I>::decl;

// A part's characters. P has constexpr static length() and at(i); each at(i) is one call the
// compiler remembers, which the hashes below read again.
template <typename P, typename S = typename cx::MakeSeq<P::length()>::type>
struct Chars;
template <typename P, size_t... I>
struct Chars<P, cx::Seq<I...> > {
  char c[sizeof...(I)];
  static constexpr Chars make() { return Chars{{P::at(I)...}}; }
};

// ---- the parts ----
template <typename D, const D* Decls>
struct HeadPart {
  static constexpr Piece piece(uint8_t k) {
    return k == 0 ? integer("{\"p\":", kProtocolVersion)
         : k == 1 ? quoted(",\"n\":\"", Decls->dev.name)
         : k == 2 ? (Decls->dev.firmwareText ? quoted(",\"fw\":\"", Decls->dev.firmwareText) : empty())
                  : literal(",\"ch\":[");
  }
  static constexpr size_t start(uint8_t k) { return k == 0 ? 0 : start((uint8_t)(k - 1)) + pieceLength(piece((uint8_t)(k - 1))); }
  static constexpr size_t length() { return start(4); }
  static constexpr char at(size_t i, uint8_t k = 3) {
    return i >= start(k) ? pieceAt(piece(k), i - start(k)) : at(i, (uint8_t)(k - 1));
  }
};
#if HUBWIRE_CX_REMEMBERS
// Channel I's entry (id I + 1) of a list: the device's channels, or the hub's (HubSide).
// A character is found with calls of scalars only: a call on a constant object, or with one as its
// argument, costs GCC 5 a copy of it, so only the per-piece functions below (remembered, one call
// a piece) touch the declaration and its pieces.
template <typename D, const D* Decls, size_t I>
struct ChannelPart {
  static constexpr Piece piece(uint8_t k) { return DeclAt<D, Decls, I>::decl.piece(k, (uint8_t)(I + 1)); }
  static constexpr size_t start(uint8_t k) { return DeclAt<D, Decls, I>::decl.pieceStart((uint8_t)(I + 1), k); }
  static constexpr const char* pre(uint8_t k) { return piece(k).pre; }
  static constexpr const char* post(uint8_t k) { return piece(k).post; }
  static constexpr size_t preLength(uint8_t k) { return cx::length(pre(k)); }
  static constexpr size_t valueEnd(uint8_t k) { return preLength(k) + valueLength(piece(k)); }
  // The value's text itself where it is written as it is (a name, unit or description without
  // escapes, a type name), else nullptr.
  static constexpr const char* plain(uint8_t k) {
    return piece(k).kind == kLiteral || (piece(k).kind == kEscaped && cx::plainLength(piece(k).text) != cx::kNotPlain)
               ? piece(k).text
               : nullptr;
  }
  static constexpr size_t length() { return start(kPiecesPerChannel); }
  // Where piece k's value and suffix start in the entry, and character i of the entry, in piece k:
  // asked with i itself, not with its offset in the piece (one call and one start() less a
  // character). The prefix and a value written as it is (most characters) in a small function, the
  // rest in another: avr-g++ 5.4 paid for the rarer cases' arms at every character.
  static constexpr size_t valueStart(uint8_t k) { return start(k) + preLength(k); }
  static constexpr size_t postStart(uint8_t k) { return start(k) + valueEnd(k); }
  static constexpr char charIn(uint8_t k, size_t i) {
    return i < valueStart(k) ? pre(k)[i - start(k)] : i < postStart(k) && plain(k) ? plain(k)[i - valueStart(k)] : restIn(k, i);
  }
  static constexpr char restIn(uint8_t k, size_t i) {
    return i >= postStart(k) ? post(k)[i - postStart(k)] : declare::valueAt(piece(k), i - valueStart(k));
  }
  // The piece holding character i. Chars::make() asks the characters in order, so character i - 1's
  // is remembered: most characters lie in the same piece (one start() asked), the others in the
  // first piece after it that ends after i (pieces may be empty). A binary search over the sixteen
  // starts, one function, cost avr-g++ 5.4 2.8 KB a character; this 1.8.
  static constexpr uint8_t pieceFrom(uint8_t k, size_t i) {
    return i < start((uint8_t)(k + 1)) ? k : pieceFrom((uint8_t)(k + 1), i);
  }
  static constexpr uint8_t pieceOf(size_t i) {
    return i == 0 ? pieceFrom(0, 0)
         : i < start((uint8_t)(pieceOf(i - 1) + 1)) ? pieceOf(i - 1)
                                                    : pieceFrom((uint8_t)(pieceOf(i - 1) + 1), i);
  }
  static constexpr char at(size_t i) { return charIn(pieceOf(i), i); }
};
#else
// Where calls are not remembered (GCC from 10 on, clang: constexpr_text.h), piece K of channel
// I's entry (id I + 1) as constants of their own, each worked out once: its prefix, value and
// suffix and their lengths. A character is then found in a few steps, without a walk over the
// pieces or the text before it (which made g++ 12 pay the square of the entry's length). GCC 5
// keeps the remembered calls above: sixteen classes a channel cost it more than the calls.
template <typename D, const D* Decls, size_t I, uint8_t K>
struct PieceConst {
  static constexpr Piece piece() { return DeclAt<D, Decls, I>::decl.piece(K, (uint8_t)(I + 1)); }
  static constexpr const char* pre = piece().pre;
  static constexpr const char* post = piece().post;
  static constexpr size_t valueStart = cx::length(pre);
  static constexpr size_t valueEnd = valueStart + valueLength(piece());
  static constexpr size_t length = valueEnd + cx::length(post);
  // The value's text itself where it is written as it is (a name, unit or description without
  // escapes, a type name), else nullptr: its characters are then worked out one by one.
  static constexpr const char* plain =
      piece().kind == kLiteral || (piece().kind == kEscaped && valueEnd - valueStart == cx::length(piece().text))
          ? piece().text
          : nullptr;
  static constexpr char at(size_t j) {
    return j < valueStart ? pre[j]
         : j >= valueEnd  ? post[j - valueEnd]
         : plain          ? plain[j - valueStart]
                          : valueAt(piece(), j - valueStart);
  }
};
template <typename D, const D* Decls, size_t I, uint8_t K>
constexpr const char* PieceConst<D, Decls, I, K>::pre;
template <typename D, const D* Decls, size_t I, uint8_t K>
constexpr const char* PieceConst<D, Decls, I, K>::post;
template <typename D, const D* Decls, size_t I, uint8_t K>
constexpr const char* PieceConst<D, Decls, I, K>::plain;

// Channel I's entry: the pieces end to end, character i found by comparing i with where each
// piece ends (constants), one call deep.
template <typename D, const D* Decls, size_t I>
struct ChannelPart {
  static_assert(kPiecesPerChannel == 16, "ChannelPart lists pieces 0..15");
  template <uint8_t K>
  using P = PieceConst<D, Decls, I, K>;
  static constexpr size_t e0 = P<0>::length, e1 = e0 + P<1>::length, e2 = e1 + P<2>::length, e3 = e2 + P<3>::length,
                          e4 = e3 + P<4>::length, e5 = e4 + P<5>::length, e6 = e5 + P<6>::length,
                          e7 = e6 + P<7>::length, e8 = e7 + P<8>::length, e9 = e8 + P<9>::length,
                          e10 = e9 + P<10>::length, e11 = e10 + P<11>::length, e12 = e11 + P<12>::length,
                          e13 = e12 + P<13>::length, e14 = e13 + P<14>::length, e15 = e14 + P<15>::length;
  static constexpr size_t length() { return e15; }
  static constexpr char at(size_t i) {
    return i < e0 ? P<0>::at(i) : i < e1 ? P<1>::at(i - e0) : i < e2 ? P<2>::at(i - e1) : i < e3 ? P<3>::at(i - e2)
         : i < e4 ? P<4>::at(i - e3) : i < e5 ? P<5>::at(i - e4) : i < e6 ? P<6>::at(i - e5) : i < e7 ? P<7>::at(i - e6)
         : i < e8 ? P<8>::at(i - e7) : i < e9 ? P<9>::at(i - e8) : i < e10 ? P<10>::at(i - e9)
         : i < e11 ? P<11>::at(i - e10) : i < e12 ? P<12>::at(i - e11) : i < e13 ? P<13>::at(i - e12)
         : i < e14 ? P<14>::at(i - e13) : P<15>::at(i - e14);
  }
};
#endif
struct HubHeadPart {  // between the channels and the hub channels
  static constexpr size_t length() { return 9; }
  static constexpr char at(size_t i) { return "],\"hub\":["[i]; }
};
struct TailPart {
  static constexpr size_t length() { return 2; }
  static constexpr char at(size_t i) { return "]}"[i]; }
};

// The hub channels (remote.h) seen as a list of channels of their own, so that the channel
// machinery writes their JSON and their records (hub_table.h).
template <typename D, const D* Decls>
struct HubSide {
  typedef Declared<decltype(Decls->hub)> Type;
  static constexpr Type value = {Decls->dev, Decls->hub, List<>{}};
};
template <typename D, const D* Decls>
constexpr typename HubSide<D, Decls>::Type HubSide<D, Decls>::value;

// The descriptor's parts in order: 0 the head, 1..N the channels, then (with hub channels) the hub
// list's head and its M entries, last the tail.
template <typename D>
constexpr size_t partCount() {
  return D::size() + 2 + (D::hubSize() > 0 ? D::hubSize() + 1 : 0);
}
template <typename D>
constexpr int partKind(size_t k) {
  return k == 0 ? 0 : k <= D::size() ? 1 : k + 1 == partCount<D>() ? 4 : k == D::size() + 1 ? 2 : 3;
}
template <typename D, const D* Decls, size_t K, int Kind = partKind<D>(K)>
struct PartAt {
  typedef HeadPart<D, Decls> Type;
};
template <typename D, const D* Decls, size_t K>
struct PartAt<D, Decls, K, 1> {
  typedef ChannelPart<D, Decls, K - 1> Type;
};
template <typename D, const D* Decls, size_t K>
struct PartAt<D, Decls, K, 2> {
  typedef HubHeadPart Type;
};
template <typename D, const D* Decls, size_t K>
struct PartAt<D, Decls, K, 3> {
  typedef ChannelPart<typename HubSide<D, Decls>::Type, &HubSide<D, Decls>::value, K - D::size() - 2> Type;
};
template <typename D, const D* Decls, size_t K>
struct PartAt<D, Decls, K, 4> {
  typedef TailPart Type;
};

// The descriptor's length from the parts' lengths alone, before any character is worked out: one
// over the hub's limit is refused (table(), tables.h) without building it (a descriptor of 254
// channels with 60-character descriptions, 34 KB, took avr-g++ 1.5 GB to build only to be refused).
template <size_t N>
struct Lengths {
  size_t n[N];
};
template <size_t N>
constexpr size_t sumOf(const Lengths<N> l, size_t lo, size_t hi) {  // passed by value: see report.h
  return hi - lo == 1 ? l.n[lo] : sumOf(l, lo, (lo + hi) / 2) + sumOf(l, (lo + hi) / 2, hi);
}
template <typename D, const D* Decls, typename S = typename cx::MakeSeq<partCount<D>()>::type>
struct FullLength;
template <typename D, const D* Decls, size_t... K>
struct FullLength<D, Decls, cx::Seq<K...> > {
  static constexpr size_t value = sumOf(Lengths<sizeof...(K)>{{PartAt<D, Decls, K>::Type::length()...}}, 0, sizeof...(K));
};
template <typename D, const D* Decls, size_t... K>
constexpr size_t FullLength<D, Decls, cx::Seq<K...> >::value;
// The parts built: all of them, or only the head when the whole is refused.
template <typename D, const D* Decls>
constexpr size_t builtParts() {
  return FullLength<D, Decls>::value <= kMaxDescriptor ? partCount<D>() : 1;
}

// Each part's characters as a constant of its own, worked out once: the JSON in flash copies it.
template <typename P>
struct PartConst {
  static constexpr Chars<P> value = Chars<P>::make();
};
template <typename P>
constexpr Chars<P> PartConst<P>::value;

// A part's character i, for the hashes: where calls are remembered (constexpr_text.h), the call that
// made the array, asked again (GCC 5 would copy the array whole at each read of one element);
// elsewhere the array's element.
#if !HUBWIRE_CX_REMEMBERS
template <typename P>
constexpr char partChar(size_t i) {
  return PartConst<P>::value.c[i];
}
#else
template <typename P>
constexpr char partChar(size_t i) {
  return P::at(i);
}
#endif

// ---- the JSON: the parts' arrays nested first to last (char arrays: no padding between them) ----
template <typename D, const D* Decls, typename S>
struct TextParts;
template <typename D, const D* Decls, size_t K>
struct TextParts<D, Decls, cx::Seq<K> > {
  Chars<typename PartAt<D, Decls, K>::Type> head;
};
template <typename D, const D* Decls, size_t K, size_t K2, size_t... R>
struct TextParts<D, Decls, cx::Seq<K, K2, R...> > {
  Chars<typename PartAt<D, Decls, K>::Type> head;
  TextParts<D, Decls, cx::Seq<K2, R...> > rest;
};
template <typename D, const D* Decls>
using JsonText = TextParts<D, Decls, typename cx::MakeSeq<builtParts<D, Decls>()>::type>;
// One flat list of the parts, which fills the nested arrays in order (brace elision): no part
// is copied more than once.
template <typename D, const D* Decls, typename S = typename cx::MakeSeq<builtParts<D, Decls>()>::type>
struct TextOf;
#if defined(__clang__)  // the braces are left out on purpose (brace elision), see above
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wmissing-braces"
#endif
template <typename D, const D* Decls, size_t... K>
struct TextOf<D, Decls, cx::Seq<K...> > {
  static constexpr JsonText<D, Decls> make() { return JsonText<D, Decls>{PartConst<typename PartAt<D, Decls, K>::Type>::value...}; }
};
#if defined(__clang__)
#pragma clang diagnostic pop
#endif
template <typename D, const D* Decls>
struct TextConst {
  static constexpr JsonText<D, Decls> value = TextOf<D, Decls>::make();
};
template <typename D, const D* Decls>
constexpr JsonText<D, Decls> TextConst<D, Decls>::value;

// ---- the hash hello carries: FNV-1a over the parts, eight characters a call; the state after
// each part is a constant of its own, so no evaluation goes deeper than one part ----
// fnv1a() written in rather than called: on GCC 5 a call costs more memory than its arithmetic.
#if HUBWIRE_CX_REMEMBERS
#define HUBWIRE_FNV(h, i) (((h) ^ (uint32_t)(uint8_t)P::at(i)) * 0x01000193UL)
#else
#define HUBWIRE_FNV(h, i) (((h) ^ (uint32_t)(uint8_t)partChar<P>(i)) * 0x01000193UL)
#endif
// The last characters, fewer than eight, apart: avr-g++ 5.4 paid for this arm at every call.
template <typename P>
constexpr uint32_t fnvTail(uint32_t h, size_t i) {
  return i < sizeof(Chars<P>) ? fnvTail<P>(HUBWIRE_FNV(h, i), i + 1) : h;
}
template <typename P>
constexpr uint32_t fnvPart(uint32_t h, size_t i = 0) {
  return i + 8 <= sizeof(Chars<P>)
             ? fnvPart<P>(HUBWIRE_FNV(HUBWIRE_FNV(HUBWIRE_FNV(HUBWIRE_FNV(HUBWIRE_FNV(HUBWIRE_FNV(HUBWIRE_FNV(HUBWIRE_FNV(
                              h, i), i + 1), i + 2), i + 3), i + 4), i + 5), i + 6), i + 7),
                          i + 8)
                                : fnvTail<P>(h, i);
}
#undef HUBWIRE_FNV
template <typename D, const D* Decls, size_t K>
struct HashAfter {  // the hash of parts 0..K-1
  static constexpr uint32_t value = fnvPart<typename PartAt<D, Decls, K - 1>::Type>(HashAfter<D, Decls, K - 1>::value);
};
template <typename D, const D* Decls>
struct HashAfter<D, Decls, 0> {
  static constexpr uint32_t value = kFnvOffset;
};
template <typename D, const D* Decls, size_t K>
constexpr uint32_t HashAfter<D, Decls, K>::value;
template <typename D, const D* Decls>
constexpr uint32_t HashAfter<D, Decls, 0>::value;
template <typename D, const D* Decls>
constexpr uint32_t hashOfText() {
  return HashAfter<D, Decls, builtParts<D, Decls>()>::value;
}

}  // namespace declare
}  // namespace hubwire

#endif
