// Declaration mistakes that depend on a value the sketch wrote (a failsafe of -1 on a uint16_t, a
// range the wrong way round, a name with a space, two channels of one name), not only on a type.
// A static_assert inside the option cannot see its argument, and failing the constant evaluation
// there would leave the declaration list no constant, burying the reason under pages of errors
// from the tables built from it. So the option records the mistake in the declaration
// (Decl::mistake()) and HUBWIRE_CHANNELS reports the first one (report.h) through InChannel below:
// its static_assert says what is wrong and the instantiation spells the channel's name,
//
//   In instantiation of 'struct hubwire::declare::InChannel<hubwire::declare::Channel<'l', 'e', 'v', 'e', 'l'>, ...>':
//   error: static assertion failed: failsafe(): a value the channel's type cannot hold (e.g. -1 for a uint16_t ...)
#ifndef HUBWIRE_CHANNELS_MISTAKES_H
#define HUBWIRE_CHANNELS_MISTAKES_H

#include <stddef.h>
#include <stdint.h>

namespace hubwire {
namespace declare {

enum Mistake : uint8_t {
  kNoMistake,
  kRangeValue,
  kRangeOrder,
  kRangeOnText,
  kFailsafeValue,
  kFailsafeOutsideRange,
  kFailsafeOnText,
  kListFailsafe,
  kBadName,
  kLongText,
  kSameName,  // found over the whole list (report.h)
};

// A channel's name as the compiler's message spells it.
template <char... C>
struct Channel {};

// Hub: a hub channel (remote(), remoteAction(), remoteEvent()).
template <typename Name, Mistake M, bool Hub>
struct InChannel {
  static_assert(M != kRangeValue, "range(): min or max is a value the channel's type cannot hold (e.g. -5 for a uint16_t, 1.5 for an int)");
  static_assert(M != kRangeOrder, "range(min, max): min is greater than max");
  static_assert(M != kRangeOnText, "range(): only a number (or an array of numbers) has a range");
  static_assert(M != kFailsafeValue, "failsafe(): a value the channel's type cannot hold (e.g. -1 for a uint16_t, 300 for a uint8_t)");
  static_assert(M != kFailsafeOutsideRange, "failsafe(): the value is outside the channel's own range()");
  static_assert(M != kFailsafeOnText, "failsafe(): only a number (or an array of numbers) has a failsafe value");
  static_assert(M != kListFailsafe, "failsafe(): a List has no failsafe value");
  static_assert(M != kBadName, "channel name: letters, digits and _ only, not starting with a digit, at most 32 characters");
  static_assert(M != kLongText, "a unit or description longer than 255 characters");
  static_assert(M != kSameName || Hub, "two channels have the same name");
  static_assert(M != kSameName || !Hub, "two hub channels have the same name");
  static const bool ok = true;
};

// Names as the descriptor allows them (docs/PROTOCOL.md 7): [A-Za-z_][A-Za-z0-9_]*, 1..32 long.
constexpr bool nameStart(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; }
constexpr bool nameRest(const char* s, size_t n = 1) {
  return *s == 0 ? n <= 32 : (nameStart(*s) || (*s >= '0' && *s <= '9')) && nameRest(s + 1, n + 1);
}
constexpr bool validName(const char* s) { return nameStart(*s) && nameRest(s + 1); }

// Texts (units, descriptions, names) are worked on by recursion, one level per character: past
// kMaxText the compiler would stop with an unclear "evaluation depth" error, so they are checked
// first, four characters a level.
const size_t kMaxText = 255;
constexpr bool shortText(const char* s, size_t n = 0) {
  return !s || n > kMaxText ? !s : !s[n] || !s[n + 1] || !s[n + 2] || !s[n + 3] || shortText(s, n + 4);
}

}  // namespace declare
}  // namespace hubwire

#endif
