// The descriptor's text, hash and digest (descriptor_text.h) worked out in steps, each checked by a
// declaration of its own in HUBWIRE_CHANNELS, with a function defined after each: GCC collects
// its garbage only between declarations (after a function's definition), and one constant made
// of the whole descriptor kept every step's garbage until the end. The steps' constants are the
// ones the JSON is made of, so nothing is worked out twice and nothing more lands in flash.
#ifndef HUBWIRE_CHANNELS_STEPS_H
#define HUBWIRE_CHANNELS_STEPS_H

#include <stddef.h>
#include <stdint.h>

#include "../wire/sha256.h"
#include "constexpr_text.h"
#include "descriptor_digest.h"
#include "descriptor_text.h"

namespace hubwire {
namespace declare {

const size_t kSteps = 8;  // of each kind: HUBWIRE_STEPS below lists 1..8

// Parts [Lo, Lo + sizeof...(J)) built: the first character of each, read.
template <size_t N>
struct FirstChars {
  char c[N];
};
template <typename D, const D* Decls, size_t Lo, typename S>
struct PartsBuilt;
template <typename D, const D* Decls, size_t Lo, size_t... J>
struct PartsBuilt<D, Decls, Lo, cx::Seq<J...> > {
  static constexpr FirstChars<sizeof...(J) + 1> value = {{PartConst<typename PartAt<D, Decls, Lo + J>::Type>::value.c[0]..., 0}};
};
template <typename D, const D* Decls, size_t Lo, size_t... J>
constexpr FirstChars<sizeof...(J) + 1> PartsBuilt<D, Decls, Lo, cx::Seq<J...> >::value;

// Step N (1..kSteps) of each kind: its share of the parts (text, hash) or of the blocks (digest).
template <typename D>
constexpr size_t stepEnd(size_t total, size_t n) {
  return total * n / kSteps;
}
template <typename D, const D* Decls, size_t N>
struct TextStep {
  static constexpr size_t lo = stepEnd<D>(builtParts<D, Decls>(), N - 1), hi = stepEnd<D>(builtParts<D, Decls>(), N);
  static constexpr bool done =
      PartsBuilt<D, Decls, lo, typename cx::MakeSeq<hi - lo>::type>::value.c[hi - lo] == 0;
};
template <typename D, const D* Decls, size_t N>
struct HashStep {
  static constexpr bool done = HashAfter<D, Decls, stepEnd<D>(builtParts<D, Decls>(), N)>::value != 0 || true;
};
template <typename D, const D* Decls, size_t N>
struct DigestStep {
  typedef DescriptorMessage<D, Decls> Msg;
  static constexpr bool done =
      sha256::detail::State<Msg, stepEnd<D>(sha256::detail::blockCount(Msg::length()), N)>::value.h[0] != 0 || true;
};

}  // namespace declare
}  // namespace hubwire

// In HUBWIRE_CHANNELS: the steps of one kind (TextStep, HashStep, DigestStep) in order, each
// followed by a function defined (never called, never emitted) where the compiler may collect.
#define HUBWIRE_STEP(Kind, n)                                                                     \
  static_assert(::hubwire::declare::Kind<decltype(declared), &declared, n>::done, "");                \
  inline void hubwire_collect_##Kind##n() {}
#define HUBWIRE_STEPS(Kind)                                                                       \
  HUBWIRE_STEP(Kind, 1)                                                                            \
  HUBWIRE_STEP(Kind, 2)                                                                            \
  HUBWIRE_STEP(Kind, 3)                                                                            \
  HUBWIRE_STEP(Kind, 4)                                                                            \
  HUBWIRE_STEP(Kind, 5)                                                                            \
  HUBWIRE_STEP(Kind, 6)                                                                            \
  HUBWIRE_STEP(Kind, 7)                                                                            \
  HUBWIRE_STEP(Kind, 8)

#endif
