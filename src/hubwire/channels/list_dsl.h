// The declarations of Lists (list.h): expose() of a List, control() and action() taking one, and
// action() returning one; the same Decl as every declaration (dsl.h), with the List's element
// type code (kListFlag, wire/values.h) and capacity. HUBWIRE_CHANNELS finds them with the others.
#ifndef HUBWIRE_CHANNELS_LIST_DSL_H
#define HUBWIRE_CHANNELS_LIST_DSL_H

#include "dsl.h"
#include "list.h"

namespace hubwire {
namespace declare {

/// A variable-length array of up to N scalars (list.h), carried with its length.
///   hubwire::List<int16_t, 8> path;   expose("path", path).writable()
template <typename T, size_t N>
constexpr Decl<T, kVariable> expose(const char* name, ::hubwire::List<T, N>& list) {
  return checkValue<T, 1 + N * sizeof(T)>(),
         Decl<T, kVariable>(name, nullptr, &list, listOf(TypeOf<T>::code), (uint8_t)N, kVoid, kReadable, nullptr, nullptr);
}

/// A control taking a List (list.h): fn gets the hub's elements.
///   void setPath(const hubwire::List<int16_t, 8>& p);   control("path", setPath)
template <typename T, size_t N>
constexpr Decl<T, kControl, void (*)(const ::hubwire::List<T, N>&)> control(const char* name,
                                                                           void (*fn)(const ::hubwire::List<T, N>&)) {
  return checkValue<T, 1 + N * sizeof(T)>(),
         Decl<T, kControl, void (*)(const ::hubwire::List<T, N>&)>(name, nullptr, nullptr, listOf(TypeOf<T>::code), (uint8_t)N,
                                                                    kVoid, kWritable, fn, &callListVoid< ::hubwire::List<T, N> >);
}
template <typename T, size_t N>
constexpr Decl<T, kControl, bool (*)(const ::hubwire::List<T, N>&)> control(const char* name,
                                                                           bool (*fn)(const ::hubwire::List<T, N>&)) {
  return checkValue<T, 1 + N * sizeof(T)>(),
         Decl<T, kControl, bool (*)(const ::hubwire::List<T, N>&)>(name, nullptr, nullptr, listOf(TypeOf<T>::code), (uint8_t)N,
                                                                    kVoid, kWritable, fn, &callListChecked< ::hubwire::List<T, N> >);
}

/// An action taking a List (list.h).
///   uint8_t sum(const hubwire::List<uint8_t, 16>& v);   action("sum", sum)
template <typename R, typename T, size_t N>
constexpr Decl<T, kAction, R (*)(const ::hubwire::List<T, N>&)> action(const char* name, R (*fn)(const ::hubwire::List<T, N>&)) {
  return checkValue<T, 1 + N * sizeof(T)>(), checkReturn<R>(),
         Decl<T, kAction, R (*)(const ::hubwire::List<T, N>&)>(name, nullptr, nullptr, listOf(TypeOf<T>::code), (uint8_t)N,
                                                                TypeOf<R>::code, kCallable, fn, &callListRet<R, ::hubwire::List<T, N> >);
}
template <typename T, size_t N>
constexpr Decl<T, kAction, void (*)(const ::hubwire::List<T, N>&)> action(const char* name,
                                                                         void (*fn)(const ::hubwire::List<T, N>&)) {
  return checkValue<T, 1 + N * sizeof(T)>(),
         Decl<T, kAction, void (*)(const ::hubwire::List<T, N>&)>(name, nullptr, nullptr, listOf(TypeOf<T>::code), (uint8_t)N, kVoid,
                                                                   kCallable, fn, &callListVoid< ::hubwire::List<T, N> >);
}

// A returned List travels whole in one answer: 1 + N elements' bytes at most HUBWIRE_MAX_RETURN.
template <typename R, size_t N>
constexpr bool checkListReturn() {
  static_assert(TypeOf<R>::code != kVoid, "Hubwire carries bool, 8/16/32-bit integers, float and double");
  static_assert(1 + N * sizeof(R) <= HUBWIRE_MAX_RETURN, "returned List larger than HUBWIRE_MAX_RETURN: raise it");
  return true;
}
/// An action returning a List (list.h), whole in one answer: 1 + N elements' bytes at most
/// HUBWIRE_MAX_RETURN.
///   hubwire::List<uint8_t, 3> pins(uint8_t bank);   action("pins", pins)
template <typename R, size_t N, typename A>
constexpr Decl<A, kAction, ::hubwire::List<R, N> (*)(A)> action(const char* name, ::hubwire::List<R, N> (*fn)(A)) {
  return checkValue<A, sizeof(A)>(), checkListReturn<R, N>(),
         Decl<A, kAction, ::hubwire::List<R, N> (*)(A)>(name, nullptr, nullptr, TypeOf<A>::code, 0, listOf(TypeOf<R>::code),
                                                        kCallable, fn, &callRetList< ::hubwire::List<R, N>, A>, 0,
                                                        (uint8_t)N);
}
template <typename R, size_t N>
constexpr Decl<NotNumeric, kAction, ::hubwire::List<R, N> (*)()> action(const char* name, ::hubwire::List<R, N> (*fn)()) {
  return checkListReturn<R, N>(),
         Decl<NotNumeric, kAction, ::hubwire::List<R, N> (*)()>(name, nullptr, nullptr, kVoid, 0, listOf(TypeOf<R>::code),
                                                               kCallable, fn, &callNoArgList< ::hubwire::List<R, N> >, 0,
                                                               (uint8_t)N);
}

}  // namespace declare
}  // namespace hubwire

#endif
