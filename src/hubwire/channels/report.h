// HUBWIRE_CHANNELS's check of its declaration list: the first declaration with a mistake
// (mistakes.h), or whose name a later one repeats, is reported through InChannel, which spells its
// name. A list without one instantiates nothing; the scan is one constexpr pass (names: n^2 compares).
#ifndef HUBWIRE_CHANNELS_REPORT_H
#define HUBWIRE_CHANNELS_REPORT_H

#include <stddef.h>

#include "constexpr_text.h"
#include "dsl.h"
#include "mistakes.h"

namespace hubwire {
namespace declare {

// The i-th declaration's mistake and name (past the end: none, "").
constexpr Mistake mistakeAt(const List<>&, size_t) { return kNoMistake; }
template <typename H, typename... R>
constexpr Mistake mistakeAt(const List<H, R...>& l, size_t i) {
  return i ? mistakeAt(l.tail, i - 1) : l.head.mistake() != kNoMistake ? l.head.mistake()
                                        : noneNamed(l.tail, l.head.name()) ? kNoMistake
                                                                           : kSameName;
}
constexpr const char* nameAt(const List<>&, size_t) { return ""; }
template <typename H, typename... R>
constexpr const char* nameAt(const List<H, R...>& l, size_t i) {
  return i ? nameAt(l.tail, i - 1) : l.head.name();
}
constexpr size_t firstMistake(const List<>&, size_t i = 0) { return i; }
template <typename H, typename... R>
constexpr size_t firstMistake(const List<H, R...>& l, size_t i = 0) {
  return mistakeAt(l, 0) != kNoMistake ? i : firstMistake(l.tail, i + 1);
}
constexpr size_t textLength(const char* s) { return *s ? 1 + textLength(s + 1) : 0; }

template <bool Hub>
struct ListOf {
  template <typename D>
  static constexpr decltype(D::list) of(const D& d) { return d.list; }
};
template <>
struct ListOf<true> {
  template <typename D>
  static constexpr decltype(D::hub) of(const D& d) { return d.hub; }
};

template <typename D, const D* Decls, bool Hub, size_t I, typename K>
struct NameOf;
template <typename D, const D* Decls, bool Hub, size_t I, size_t... K>
struct NameOf<D, Decls, Hub, I, cx::Seq<K...> > {
  typedef Channel<nameAt(ListOf<Hub>::of(*Decls), I)[K]...> type;
};

template <typename D, const D* Decls, bool Hub, size_t I = firstMistake(ListOf<Hub>::of(*Decls)),
          bool Found = (I < decltype(ListOf<Hub>::of(*Decls))::size)>
struct Report {
  static const bool ok = true;
};
template <typename D, const D* Decls, bool Hub, size_t I>
struct Report<D, Decls, Hub, I, true>
    : InChannel<typename NameOf<D, Decls, Hub, I, typename cx::MakeSeq<textLength(nameAt(ListOf<Hub>::of(*Decls), I))>::type>::type,
                mistakeAt(ListOf<Hub>::of(*Decls), I), Hub> {};

}  // namespace declare
}  // namespace hubwire

#endif
