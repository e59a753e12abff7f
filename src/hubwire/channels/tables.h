// The flash tables a declaration list becomes, and their checks: the descriptor JSON with its hash
// and digest (descriptor_text.h), one ChannelInfo per channel and the copies it points to (a
// struct's layout, the function called, range and failsafe values). table() checks what needs the
// whole list (names unique, texts short, descriptor size) and returns the ChannelTable begin() takes.
#ifndef HUBWIRE_CHANNELS_TABLES_H
#define HUBWIRE_CHANNELS_TABLES_H

#include <stddef.h>
#include <stdint.h>

#include "../wire/messages.h"
#include "channel.h"
#include "constexpr_text.h"
#include "descriptor_digest.h"
#include "descriptor_text.h"
#include "dsl.h"

namespace hubwire {
namespace declare {

template <typename T, Kind K, typename C>
constexpr bool textsShort(const Decl<T, K, C>& d) {
  return shortText(d.name()) && shortText(d.unitText()) && shortText(d.descriptionText()) && shortText(d.layout());
}
constexpr bool allTextsShortIn(const List<>&) { return true; }
template <typename H, typename... R>
constexpr bool allTextsShortIn(const List<H, R...>& l) {
  return textsShort(l.head) && allTextsShortIn(l.tail);
}
template <typename... T>
constexpr bool allTextsShort(const List<T...>& l) { return allTextsShortIn(copyOf(l)); }

// Is no channel in l called name? Are all names in l different?
constexpr bool noneNamed(const List<>&, const char*) { return true; }
template <typename H, typename... R>
constexpr bool noneNamed(const List<H, R...>& l, const char* name) {
  return !cx::equal(l.head.name(), name) && noneNamed(l.tail, name);
}
constexpr bool namesUniqueIn(const List<>&) { return true; }
template <typename H, typename... R>
constexpr bool namesUniqueIn(const List<H, R...>& l) {
  return noneNamed(l.tail, l.head.name()) && namesUniqueIn(l.tail);
}
template <typename... T>
constexpr bool namesUnique(const List<T...>& l) { return namesUniqueIn(copyOf(l)); }

// The same, for a sketch's list, without walking the list for every pair of names (32,000 walks
// for 254 channels): each name's FNV-1a hash is worked out once, the hashes are compared in one
// array passed by value (reading a constant array would copy it at every read), and only where
// two are equal are the names compared as above.
constexpr uint32_t nameHash(const char* s, uint32_t h = kFnvOffset) { return *s ? nameHash(s + 1, fnv1a(h, (uint8_t)*s)) : h; }
template <typename D, const D* Decls, size_t I>
struct NameHash {
  static constexpr uint32_t value = nameHash(DeclAt<D, Decls, I>::decl.name());
};
template <typename D, const D* Decls, size_t I>
constexpr uint32_t NameHash<D, Decls, I>::value;
template <size_t N>
struct Hashes {
  uint32_t h[N];
};
template <size_t N>
constexpr bool hashLater(const Hashes<N>& a, size_t i, size_t j) {  // a.h[i] again at j or after? four a call
  return j < N && (a.h[j] == a.h[i] || (j + 1 < N && a.h[j + 1] == a.h[i]) || (j + 2 < N && a.h[j + 2] == a.h[i]) ||
                   (j + 3 < N && a.h[j + 3] == a.h[i]) || hashLater(a, i, j + 4));
}
template <size_t N>
constexpr bool hashTwice(const Hashes<N>& a, size_t i = 0) { return i < N && (hashLater(a, i, i + 1) || hashTwice(a, i + 1)); }
template <typename D, const D* Decls, typename S = typename cx::MakeSeq<D::size()>::type>
struct NamesUnique;
template <typename D, const D* Decls>
struct NamesUnique<D, Decls, cx::Seq<> > {
  static constexpr bool value = true;
};
template <typename D, const D* Decls, size_t... I>
struct NamesUnique<D, Decls, cx::Seq<I...> > {
  static constexpr bool value =
      !hashTwice(Hashes<sizeof...(I)>{{NameHash<D, Decls, I>::value...}}) || namesUnique(Decls->list);
};
template <typename D, const D* Decls>
constexpr bool NamesUnique<D, Decls, cx::Seq<> >::value;
template <typename D, const D* Decls, size_t... I>
constexpr bool NamesUnique<D, Decls, cx::Seq<I...> >::value;

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
// Every channel's Extra as a direct base (not a chain of n classes, each converting to the next:
// n^2 steps while compiling 254 channels).
template <typename D, const D* Decls, typename S = typename cx::MakeSeq<D::size()>::type>
struct Extras;
template <typename D, const D* Decls, size_t... I>
struct Extras<D, Decls, cx::Seq<I...> > : Extra<D, Decls, I>... {
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
  typedef JsonAndDigest<D, Decls> JsonType;  // not Json<>: the hub side (hub_table.h) needs no JSON of its own
  typedef Extras<D, Decls> ExtrasType;
  typedef typename Infos<D, Decls>::Type InfosType;
  static constexpr JsonType json() { return Json<D, Decls>::value; }
  static constexpr InfosType infos(const ExtrasType& e) { return Infos<D, Decls>::make(e); }
};

// The features of the whole list (features.h).
constexpr uint16_t featuresIn(const List<>&) { return 0; }
template <typename H, typename... R>
constexpr uint16_t featuresIn(const List<H, R...>& l) {
  return (uint16_t)(l.head.features() | featuresIn(l.tail));
}
template <typename... T>
constexpr uint16_t featuresOf(const List<T...>& l) { return featuresIn(copyOf(l)); }

// The reassembly buffer the list needs: its largest value written or passed in that does not fit
// a frame (session/fragments.h), 0 for none.
constexpr uint16_t largeInIn(const List<>&) { return 0; }
constexpr uint16_t larger(uint16_t a, uint16_t b) { return a > b ? a : b; }
template <typename H, typename... R>
constexpr uint16_t largeInIn(const List<H, R...>& l) {
  return larger(l.head.largeIn(), largeInIn(l.tail));  // once each: a list of 254 stays linear
}
template <typename... T>
constexpr uint16_t largeInOf(const List<T...>& l) { return largeInIn(copyOf(l)); }

// json and infos: the sketch's copies of Stored<D, Decls>::json() and infos(), in flash.
template <typename D, const D* Decls>
constexpr ChannelTable table(const typename Stored<D, Decls>::JsonType& json,
                             const typename Stored<D, Decls>::InfosType& infos) {
  static_assert(allTextsShort(Decls->list) && shortText(Decls->dev.name) && shortText(Decls->dev.firmwareText),
                "a name, unit, description, layout or firmware text longer than 255 characters");
  static_assert(allTextsShort(Decls->hub), "a hub channel's name, unit or description longer than 255 characters");
  static_assert(FullLength<D, Decls>::value <= kMaxDescriptor, "descriptor longer than the 16 KiB a hub accepts");
  static_assert(sizeof(JsonText<D, Decls>) == FullLength<D, Decls>::value || FullLength<D, Decls>::value > kMaxDescriptor,
                "the JSON is as long as its parts");
  static_assert(sizeof(JsonAndDigest<D, Decls>) == kHelloFixed + kDigestSize + sizeof(JsonText<D, Decls>),
                "hello's fixed fields, the digest and the JSON lie end to end");
  return ChannelTable{json.text.head.c, hashOfText<D, Decls>(), (uint16_t)sizeof(JsonText<D, Decls>), infos.v,
                      D::size()};
}

}  // namespace declare
}  // namespace hubwire

#endif
