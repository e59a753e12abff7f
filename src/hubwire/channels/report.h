// HUBWIRE_CHANNELS's check of its declaration list: the first declaration with a mistake
// (mistakes.h), else the first whose name a later one repeats, is reported through InChannel,
// which spells its name. It costs the compiler little (the tables read each declaration through
// DeclAt anyway): one array of the declarations' mistakes, and the names' hashes (NamesUnique);
// only a list with a repeated name is walked pair by pair, to find which.
#ifndef HUBWIRE_CHANNELS_REPORT_H
#define HUBWIRE_CHANNELS_REPORT_H

#include <stddef.h>
#include <stdint.h>

#include "constexpr_text.h"
#include "descriptor_text.h"
#include "mistakes.h"
#include "tables.h"

namespace hubwire {
namespace declare {

// The index of the first non-zero code before the end mark (N - 1: none). Passed by value: GCC 5 would copy a constant
// array at every read.
template <size_t N>
struct Codes {
  uint8_t m[N];
};
template <size_t N>
constexpr size_t firstSet(const Codes<N> c, size_t i = 0) {
  return i + 1 < N && c.m[i] == kNoMistake ? firstSet(c, i + 1) : i;  // m[N - 1]: an end mark
}
// The index of the first declaration whose name a later one repeats (the list's size: none).
constexpr size_t firstRepeated(const List<>&, size_t i = 0) { return i; }
template <typename H, typename... R>
constexpr size_t firstRepeated(const List<H, R...>& l, size_t i = 0) {
  return noneNamed(l.tail, l.head.name()) ? firstRepeated(l.tail, i + 1) : i;
}
constexpr size_t textLength(const char* s) { return *s ? 1 + textLength(s + 1) : 0; }

template <typename D, const D* Decls, typename S = typename cx::MakeSeq<D::size()>::type>
struct FirstMistake;
template <typename D, const D* Decls, size_t... I>
struct FirstMistake<D, Decls, cx::Seq<I...> > {
  static constexpr size_t value = firstSet(Codes<sizeof...(I) + 1>{{(uint8_t)DeclAt<D, Decls, I>::decl.mistake()..., 0}});
};
template <typename D, const D* Decls, size_t... I>
constexpr size_t FirstMistake<D, Decls, cx::Seq<I...> >::value;

// The I-th declaration's name, spelled for the compiler's message.
template <typename D, const D* Decls, size_t I, typename K = typename cx::MakeSeq<textLength(DeclAt<D, Decls, I>::decl.name())>::type>
struct NameOf;
template <typename D, const D* Decls, size_t I, size_t... K>
struct NameOf<D, Decls, I, cx::Seq<K...> > {
  typedef Channel<DeclAt<D, Decls, I>::decl.name()[K]...> type;
};

// No declaration has a mistake of its own: are the names unique?
template <typename D, const D* Decls, bool Hub, bool Unique = NamesUnique<D, Decls>::value>
struct ReportRepeated {
  static const bool ok = true;
};
template <typename D, const D* Decls, bool Hub, bool Unique>
const bool ReportRepeated<D, Decls, Hub, Unique>::ok;
template <typename D, const D* Decls, bool Hub>
struct ReportRepeated<D, Decls, Hub, false>
    : InChannel<typename NameOf<D, Decls, firstRepeated(copyOf(Decls->list))>::type, kSameName, Hub> {};

/// ok when the list (D, Decls) has no mistake; else the compiler stops in InChannel, naming it.
template <typename D, const D* Decls, bool Hub, size_t I = FirstMistake<D, Decls>::value, bool Found = (I < D::size())>
struct Report : ReportRepeated<D, Decls, Hub> {};
template <typename D, const D* Decls, bool Hub, size_t I>
struct Report<D, Decls, Hub, I, true>
    : InChannel<typename NameOf<D, Decls, I>::type, DeclAt<D, Decls, I>::decl.mistake(), Hub> {};

// Both lists of a sketch: its channels and its hub channels.
template <typename D, const D* Decls>
struct Reported {
  static const bool ok = Report<D, Decls, false>::ok &&
                         Report<typename HubSide<D, Decls>::Type, &HubSide<D, Decls>::value, true>::ok;
};

}  // namespace declare
}  // namespace hubwire

#endif
