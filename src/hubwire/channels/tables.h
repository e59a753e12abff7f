// The flash tables a declaration list becomes, and their checks: the descriptor JSON as char
// arrays laid end to end, its hash and digest, one ChannelInfo per channel and the copies it points to (a
// struct's layout, the function called, range and failsafe values). table() checks what needs the
// whole list (names unique, texts short, descriptor size) and returns the ChannelTable begin() takes.
#ifndef HUBWIRE_CHANNELS_TABLES_H
#define HUBWIRE_CHANNELS_TABLES_H

#include <stddef.h>
#include <stdint.h>

#include "../wire/messages.h"
#include "../wire/sha256.h"
#include "channel.h"
#include "constexpr_text.h"
#include "dsl.h"

namespace hubwire {
namespace declare {

template <typename T, Kind K, typename C>
constexpr bool textsShort(const Decl<T, K, C>& d) {
  return shortText(d.name()) && shortText(d.unitText()) && shortText(d.descriptionText()) && shortText(d.layout());
}
constexpr bool allTextsShort(const List<>&) { return true; }
template <typename H, typename... R>
constexpr bool allTextsShort(const List<H, R...>& l) {
  return textsShort(l.head) && allTextsShort(l.tail);
}

// The i-th declaration of a list (0-based).
template <size_t I>
struct At {
  template <typename L>
  static constexpr auto of(const L& l) -> decltype(At<I - 1>::of(l.tail)) {
    return At<I - 1>::of(l.tail);
  }
};
template <>
struct At<0> {
  template <typename L>
  static constexpr auto of(const L& l) -> decltype(l.head) {
    return l.head;
  }
};

// The I-th declaration of a sketch's list, looked up once: At<I> walks the list, which every
// character of the JSON (or every use) repeating it would make cost n^2 while compiling.
template <typename D, const D* Decls, size_t I>
struct DeclAt {
  typedef decltype(At<I>::of(Decls->list)) Type;
  static constexpr Type decl = At<I>::of(Decls->list);
};
template <typename D, const D* Decls, size_t I>
constexpr typename DeclAt<D, Decls, I>::Type DeclAt<D, Decls, I>::decl;

// ---- the descriptor in flash: one char array per part, laid end to end (no padding between
// char arrays), so that no character is computed twice and no recursion runs the whole length ----
// P has constexpr static length() and at(i).
template <typename P, typename S = typename cx::MakeSeq<P::length()>::type>
struct Chars;
template <typename P, size_t... I>
struct Chars<P, cx::Seq<I...> > {
  char c[sizeof...(I)];
  static constexpr Chars make() { return Chars{{P::at(I)...}}; }
};

template <typename D, const D* Decls>
struct HeadPart {
  static constexpr Piece piece(uint8_t k) {
    return k == 0 ? integer("{\"p\":", kProtocolVersion)
         : k == 1 ? quoted(",\"n\":\"", Decls->dev.name)
         : k == 2 ? (Decls->dev.firmwareText ? quoted(",\"fw\":\"", Decls->dev.firmwareText) : empty())
                  : literal(",\"ch\":[");
  }
  static constexpr size_t length(uint8_t k = 0) { return k == 4 ? 0 : pieceLength(piece(k)) + length((uint8_t)(k + 1)); }
  static constexpr char at(size_t i, uint8_t k = 0) {
    return i < pieceLength(piece(k)) ? pieceAt(piece(k), i) : at(i - pieceLength(piece(k)), (uint8_t)(k + 1));
  }
};
template <typename D, const D* Decls, size_t I>
struct ChannelPart {
  static constexpr size_t length() { return DeclAt<D, Decls, I>::decl.jsonLength((uint8_t)(I + 1)); }
  static constexpr char at(size_t i) { return DeclAt<D, Decls, I>::decl.jsonAt((uint8_t)(I + 1), i); }
};
struct TailPart {
  static constexpr size_t length() { return 2; }
  static constexpr char at(size_t i) { return "]}"[i]; }
};

// Each part's characters as a constant of its own, worked out once: the JSON in flash copies them
// and the digest reads them. avr-gcc 5 copies a constant array whole at each read of an element, so
// the digest reads parts (tens of bytes), never the whole JSON (up to 16 KiB, quadratic).
template <typename P>
struct PartConst {
  static constexpr Chars<P> value = Chars<P>::make();
};
template <typename P>
constexpr Chars<P> PartConst<P>::value;

// What follows the channels: "]}", or the "hub" list and then "]}" (hub_table.h).
template <typename D, const D* Decls, bool Hub = (D::hubSize() > 0)>
struct Tail {
  typedef Chars<TailPart> Text;
  static constexpr Text make() { return PartConst<TailPart>::value; }
};

template <typename D, const D* Decls, typename S>
struct Channels;
template <typename D, const D* Decls>
struct Channels<D, Decls, cx::Seq<> > {
  typename Tail<D, Decls>::Text tail;
  static constexpr Channels make() { return Channels{Tail<D, Decls>::make()}; }
};
template <typename D, const D* Decls, size_t I, size_t... R>
struct Channels<D, Decls, cx::Seq<I, R...> > {
  Chars<ChannelPart<D, Decls, I> > first;
  Channels<D, Decls, cx::Seq<R...> > rest;
  static constexpr Channels make() {
    return Channels{PartConst<ChannelPart<D, Decls, I> >::value, Channels<D, Decls, cx::Seq<R...> >::make()};
  }
};
template <typename D, const D* Decls>
struct JsonText {
  Chars<HeadPart<D, Decls> > head;
  Channels<D, Decls, typename cx::MakeSeq<D::size()>::type> body;
};

// ---- the descriptor as one message for sha256.h: the parts (0 the head, K the channel K-1, then
// the tail) joined as a balanced tree, so that reading a character goes log2(parts) levels deep ----
template <typename P>
struct PartMessage {
  static constexpr size_t length() { return sizeof(Chars<P>); }
  static constexpr char at(size_t i) { return PartConst<P>::value.c[i]; }
};
template <typename D, const D* Decls, size_t K>
struct PartAt {
  typedef ChannelPart<D, Decls, K - 1> Type;
};
template <typename D, const D* Decls>
struct PartAt<D, Decls, 0> {
  typedef HeadPart<D, Decls> Type;
};
template <typename D, const D* Decls, size_t Lo, size_t Hi, bool One = Hi - Lo == 1>
struct Parts : sha256::Concat<Parts<D, Decls, Lo, (Lo + Hi) / 2>, Parts<D, Decls, (Lo + Hi) / 2, Hi> > {};
template <typename D, const D* Decls, size_t Lo, size_t Hi>
struct Parts<D, Decls, Lo, Hi, true> : PartMessage<typename PartAt<D, Decls, Lo>::Type> {};
template <typename D, const D* Decls, bool Hub = (D::hubSize() > 0)>
struct TailMessage : PartMessage<TailPart> {};
template <typename D, const D* Decls>
struct DescriptorMessage : sha256::Concat<Parts<D, Decls, 0, D::size() + 1>, TailMessage<D, Decls> > {};

// The descriptor's hash (hello carries it), over the characters above: eight a level, one level a
// channel, so that the compiler's depth limit is far away.
constexpr uint32_t fnvChars(const char* c, size_t n, uint32_t h, size_t i = 0) {
  return i + 8 <= n ? fnvChars(c, n,
                               fnv1a(fnv1a(fnv1a(fnv1a(fnv1a(fnv1a(fnv1a(fnv1a(h, (uint8_t)c[i]), (uint8_t)c[i + 1]),
                                                                   (uint8_t)c[i + 2]), (uint8_t)c[i + 3]),
                                                       (uint8_t)c[i + 4]), (uint8_t)c[i + 5]), (uint8_t)c[i + 6]),
                                     (uint8_t)c[i + 7]),
                               i + 8)
         : i < n ? fnvChars(c, n, fnv1a(h, (uint8_t)c[i]), i + 1)
                 : h;
}
constexpr uint32_t hashOf(const Chars<TailPart>& t, uint32_t h) { return fnvChars(t.c, sizeof(t.c), h); }
template <typename D, const D* Decls>
constexpr uint32_t hashOf(const Channels<D, Decls, cx::Seq<> >& b, uint32_t h) {
  return hashOf(b.tail, h);
}
template <typename D, const D* Decls, size_t I, size_t... R>
constexpr uint32_t hashOf(const Channels<D, Decls, cx::Seq<I, R...> >& b, uint32_t h) {
  return hashOf(b.rest, fnvChars(b.first.c, sizeof(b.first.c), h));
}

// The JSON as a constant of its own: the hash and hello's fields are worked out from it.
template <typename D, const D* Decls>
struct TextOf {
  static constexpr JsonText<D, Decls> value = {PartConst<HeadPart<D, Decls> >::value,
                                               decltype(JsonText<D, Decls>::body)::make()};
};
template <typename D, const D* Decls>
constexpr JsonText<D, Decls> TextOf<D, Decls>::value;
template <typename D, const D* Decls>
constexpr uint32_t hashOfText() {
  return hashOf(TextOf<D, Decls>::value.body,
                fnvChars(TextOf<D, Decls>::value.head.c, sizeof(TextOf<D, Decls>::value.head.c), kFnvOffset));
}

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
                                   TextOf<D, Decls>::value};
};
template <typename D, const D* Decls>
constexpr typename Json<D, Decls>::Stored Json<D, Decls>::value;

// A struct channel's layout, compiled to two bytes a field (layout.h) into flash for the session's
// struct codec.
template <typename D, const D* Decls, size_t I>
struct LayoutPart {
  static constexpr size_t length() { return compiledLayoutLength(DeclAt<D, Decls, I>::decl.layout()); }
  static constexpr char at(size_t i) { return (char)compiledLayoutAt(DeclAt<D, Decls, I>::decl.layout(), i); }
};

template <typename T, Kind K, typename C>
constexpr bool isStruct(const Decl<T, K, C>*) { return false; }
template <Kind K, typename C>
constexpr bool isStruct(const Decl<StructValue, K, C>*) { return true; }

// The flash copies a record points to: a struct's layout, the function called (with its own type),
// range and failsafe values. Each is a base of the channel's Extra, empty where it does not apply,
// so the sketch's one object of them all (Extras, HUBWIRE_CHANNELS defines it) holds only what does.
template <typename D, const D* Decls, size_t I, bool IsStruct = isStruct((typename DeclAt<D, Decls, I>::Type*)nullptr)>
struct LayoutStore {
  constexpr LayoutStore() {}
  constexpr const char* layout() const { return nullptr; }
};
template <typename D, const D* Decls, size_t I>
struct LayoutStore<D, Decls, I, true> {
  static_assert(layoutSize(DeclAt<D, Decls, I>::decl.layout()) == DeclAt<D, Decls, I>::decl.memSize(),
                "struct layout does not match the struct: name:type[count] for every field, in order, "
                "types bool u8 i8 u16 i16 u32 i32 f32 f64 (e.g. \"ax:f32,gyro:i16[3]\")");
  constexpr LayoutStore() : text(Chars<LayoutPart<D, Decls, I> >::make()) {}
  constexpr const char* layout() const { return text.c; }
  Chars<LayoutPart<D, Decls, I> > text;
};
template <typename D, const D* Decls, size_t I, bool HasCall = DeclAt<D, Decls, I>::decl.hasCall()>
struct CallStore {
  constexpr CallStore() {}
  constexpr const void* call() const { return nullptr; }
};
template <typename D, const D* Decls, size_t I>
struct CallStore<D, Decls, I, true> {
  constexpr CallStore() : fn(DeclAt<D, Decls, I>::decl.call()) {}
  constexpr const void* call() const { return &fn; }
  decltype(DeclAt<D, Decls, I>::decl.call()) fn;
};
template <typename D, const D* Decls, size_t I, bool HasLimits = DeclAt<D, Decls, I>::decl.hasLimits()>
struct LimitsStore {
  constexpr LimitsStore() {}
  constexpr const ChannelLimits* limits() const { return nullptr; }
};
template <typename D, const D* Decls, size_t I>
struct LimitsStore<D, Decls, I, true> {
  constexpr LimitsStore() : lim(DeclAt<D, Decls, I>::decl.limits()) {}
  constexpr const ChannelLimits* limits() const { return &lim; }
  ChannelLimits lim;
};
template <typename D, const D* Decls, size_t I>
struct Extra : LayoutStore<D, Decls, I>, CallStore<D, Decls, I>, LimitsStore<D, Decls, I> {
  constexpr Extra() {}
};
template <typename D, const D* Decls, typename S = typename cx::MakeSeq<D::size()>::type>
struct Extras;
template <typename D, const D* Decls>
struct Extras<D, Decls, cx::Seq<> > {
  constexpr Extras() {}
};
template <typename D, const D* Decls, size_t I, size_t... R>
struct Extras<D, Decls, cx::Seq<I, R...> > : Extra<D, Decls, I>, Extras<D, Decls, cx::Seq<R...> > {
  constexpr Extras() {}
};

template <typename D, const D* Decls, size_t I>
struct InfoOf {
  static constexpr ChannelInfo make(const Extra<D, Decls, I>& e) {
    return DeclAt<D, Decls, I>::decl.info(e.layout(), e.call(), e.limits());
  }
};

template <size_t N>
struct InfoArray {
  ChannelInfo v[N];
};
template <typename D, const D* Decls, typename S = typename cx::MakeSeq<D::size()>::type>
struct Infos;
template <typename D, const D* Decls, size_t... I>
struct Infos<D, Decls, cx::Seq<I...> > {
  typedef InfoArray<sizeof...(I) ? sizeof...(I) : 1> Type;
  static constexpr Type make(const Extras<D, Decls>& e) { return Type{{InfoOf<D, Decls, I>::make(e)...}}; }
};

// The JSON (after its digest), the records and what they point to, as HUBWIRE_CHANNELS stores them:
// in objects of the sketch's own, not as members of these templates, because GCC ignores a section
// attribute on a template's static member (it keeps it in .rodata, which Teensy 4 copies to RAM).
template <typename D, const D* Decls>
struct Stored {
  typedef typename Json<D, Decls>::Stored JsonType;
  typedef Extras<D, Decls> ExtrasType;
  typedef typename Infos<D, Decls>::Type InfosType;
  static constexpr JsonType json() { return Json<D, Decls>::value; }
  static constexpr InfosType infos(const ExtrasType& e) { return Infos<D, Decls>::make(e); }
};

// The features of the whole list (features.h).
constexpr uint16_t featuresOf(const List<>&) { return 0; }
template <typename H, typename... R>
constexpr uint16_t featuresOf(const List<H, R...>& l) {
  return (uint16_t)(l.head.features() | featuresOf(l.tail));
}

// The reassembly buffer the list needs: its largest value written or passed in that does not fit
// a frame (session/fragments.h), 0 for none.
constexpr uint16_t largeInOf(const List<>&) { return 0; }
constexpr uint16_t larger(uint16_t a, uint16_t b) { return a > b ? a : b; }
template <typename H, typename... R>
constexpr uint16_t largeInOf(const List<H, R...>& l) {
  return larger(l.head.largeIn(), largeInOf(l.tail));  // once each: a list of 254 stays linear
}

// json and infos: the sketch's copies of Stored<D, Decls>::json() and infos(), in flash.
template <typename D, const D* Decls>
constexpr ChannelTable table(const typename Stored<D, Decls>::JsonType& json,
                             const typename Stored<D, Decls>::InfosType& infos) {
  static_assert(allTextsShort(Decls->list) && shortText(Decls->dev.name) && shortText(Decls->dev.firmwareText),
                "a name, unit, description, layout or firmware text longer than 255 characters");
  static_assert(allTextsShort(Decls->hub), "a hub channel's name, unit or description longer than 255 characters");
  static_assert(sizeof(JsonText<D, Decls>) <= kMaxDescriptor, "descriptor longer than the 16 KiB a hub accepts");
  static_assert(sizeof(JsonAndDigest<D, Decls>) == kHelloFixed + kDigestSize + sizeof(JsonText<D, Decls>),
                "hello's fixed fields, the digest and the JSON lie end to end");
  return ChannelTable{json.text.head.c, hashOfText<D, Decls>(), (uint16_t)sizeof(JsonText<D, Decls>), infos.v,
                      D::size()};
}

}  // namespace declare
}  // namespace hubwire

#endif
