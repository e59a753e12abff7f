// The declaration DSL a sketch writes inside HUBWIRE_CHANNELS (declare.h): expose(), control(),
// action(), event() and device(), each a constexpr Decl whose options (writable(), range(),
// unit(), failsafe() ...) return a changed copy; a declaration that cannot work fails to compile
// here, saying why (class Decl: decl.h). declared() gathers them into a list for tables.h.
#ifndef HUBWIRE_CHANNELS_DSL_H
#define HUBWIRE_CHANNELS_DSL_H

#include <stddef.h>
#include <stdint.h>

#include "constexpr_text.h"
#include "decl.h"

namespace hubwire {
namespace declare {

// ---- the declarations ----
// A value larger than one frame travels in fragments (PROTOCOL.md 12); HUBWIRE_MAX_VALUE bounds it.
template <typename T, size_t Bytes>
constexpr bool checkValue() {
  static_assert(TypeOf<T>::code != kVoid, "Hubwire carries bool, 8/16/32-bit integers, float and double");
  static_assert(Bytes <= HUBWIRE_MAX_VALUE, "value larger than HUBWIRE_MAX_VALUE (1024 bytes by default): raise it");
  return true;
}
template <typename R>
constexpr bool checkReturn() {
  static_assert(TypeOf<R>::code != kVoid, "Hubwire carries bool, 8/16/32-bit integers, float and double");
  static_assert(sizeof(R) <= HUBWIRE_MAX_RETURN, "return value larger than HUBWIRE_MAX_RETURN: raise it");
  return true;
}

/// A variable (scalar, fixed array, char[] string): readable; options make it writable etc.
///   expose("battery", batteryMv)
template <typename T>
constexpr Decl<T, kVariable> expose(const char* name, T& var) {
  return checkValue<T, sizeof(T)>(), Decl<T, kVariable>(name, nullptr, &var, TypeOf<T>::code, 0, kVoid, kReadable, nullptr, nullptr);
}
template <typename T, size_t N>
constexpr Decl<T, kVariable> expose(const char* name, T (&arr)[N]) {
  static_assert(N <= 255, "arrays hold at most 255 elements");
  return checkValue<T, sizeof(arr)>(), Decl<T, kVariable>(name, nullptr, arr, TypeOf<T>::code, (uint8_t)N, kVoid, kReadable, nullptr, nullptr);
}
template <size_t N>
constexpr Decl<NotNumeric, kVariable> expose(const char* name, char (&str)[N]) {
  static_assert(N >= 2 && N <= 256, "a string channel needs a char[2..256] (one byte for the NUL)");
  static_assert(N + kSampleHeader <= HUBWIRE_MAX_PAYLOAD, "string longer than HUBWIRE_MAX_PAYLOAD - 3: raise it");
  return Decl<NotNumeric, kVariable>(name, nullptr, str, kStr, (uint8_t)(N - 1), kVoid, kReadable, nullptr, nullptr);
}
/// A struct with named fields, laid out by text (name:type[count] per field, in order).
///   expose("imu", imu, "ax:f32,ay:f32,az:f32,gyro:i16[3]")
template <typename T>
constexpr Decl<StructValue, kVariable> expose(const char* name, T& var, const char* layout) {
  static_assert(sizeof(T) <= HUBWIRE_MAX_VALUE, "struct larger than HUBWIRE_MAX_VALUE (1024 bytes by default): raise it");
  return Decl<StructValue, kVariable>(name, layout, &var, kStruct, 0, kVoid, kReadable, nullptr, nullptr,
                                      (uint16_t)sizeof(T));
}

/// A write-only control: the hub's value is handed to fn. A bool-returning fn may refuse it.
///   control("led", setLed)
template <typename T>
constexpr Decl<T, kControl, void (*)(T)> control(const char* name, void (*fn)(T)) {
  return checkValue<T, sizeof(T)>(), Decl<T, kControl, void (*)(T)>(name, nullptr, nullptr, TypeOf<T>::code, 0, kVoid, kWritable, fn, &callVoid<T>);
}
template <typename T>
constexpr Decl<T, kControl, bool (*)(T)> control(const char* name, bool (*fn)(T)) {
  return checkValue<T, sizeof(T)>(), Decl<T, kControl, bool (*)(T)>(name, nullptr, nullptr, TypeOf<T>::code, 0, kVoid, kWritable, fn, &callChecked<T>);
}

/// A callable action: the hub calls fn with an argument (or none) and gets its return value.
///   action("beep", beep)
template <typename R, typename A>
constexpr Decl<A, kAction, R (*)(A)> action(const char* name, R (*fn)(A)) {
  return checkValue<A, sizeof(A)>(), checkReturn<R>(),
         Decl<A, kAction, R (*)(A)>(name, nullptr, nullptr, TypeOf<A>::code, 0, TypeOf<R>::code, kCallable, fn, &callRet<R, A>);
}
template <typename A>
constexpr Decl<A, kAction, void (*)(A)> action(const char* name, void (*fn)(A)) {
  return checkValue<A, sizeof(A)>(), Decl<A, kAction, void (*)(A)>(name, nullptr, nullptr, TypeOf<A>::code, 0, kVoid, kCallable, fn, &callVoid<A>);
}
template <typename R>
constexpr Decl<NotNumeric, kAction, R (*)()> action(const char* name, R (*fn)()) {
  return checkReturn<R>(), Decl<NotNumeric, kAction, R (*)()>(name, nullptr, nullptr, kVoid, 0, TypeOf<R>::code, kCallable, fn, &callNoArg<R>);
}
constexpr Decl<NotNumeric, kAction> action(const char* name, void (*fn)()) {
  return Decl<NotNumeric, kAction>(name, nullptr, nullptr, kVoid, 0, kVoid, kCallable, fn, &callPlain);
}

/// An event the sketch emits with emit(); the hub is told exactly once.
///   event("bumper", bumper)
template <typename T>
constexpr Decl<NotNumeric, kEvent> event(const char* name, Event<T>& ev) {
  static_assert(sizeof(T) <= HUBWIRE_EVENT_MAX_PAYLOAD,
                "event value larger than HUBWIRE_EVENT_MAX_PAYLOAD: raise it (events are never fragmented: emit a "
                "notice and let the hub read a large value)");
  return checkValue<T, sizeof(T)>(), Decl<NotNumeric, kEvent>(name, nullptr, &ev.id, TypeOf<T>::code, 0, kVoid, kEventAccess, nullptr, nullptr);
}

/// The device itself: its name and, optionally, the firmware version the hub shows.
///   HUBWIRE_CHANNELS(channels, device("rover").firmware("1.0.0"), ...)
struct DeviceName {
  constexpr DeviceName(const char* n) : name(n), firmwareText(nullptr) {}  // NOLINT: a name alone
  constexpr DeviceName(const char* n, const char* fw) : name(n), firmwareText(fw) {}
  constexpr DeviceName firmware(const char* fw) const { return DeviceName(name, fw); }
  const char* name;
  const char* firmwareText;
};
constexpr DeviceName device(const char* name) { return DeviceName(name); }

// ---- the list of declarations ----
template <typename... D>
struct List;
template <>
struct List<> {
  static const uint8_t size = 0;
};
template <typename H, typename... R>
struct List<H, R...> {
  static const uint8_t size = (uint8_t)(1 + sizeof...(R));
  H head;
  List<R...> tail;
};
// A copy of a constant, to walk: GCC 5 copies a constant whole at every read of a part of it, so
// a walk over the sketch's list (254 reads) reads this temporary, read in place, instead.
template <typename L>
constexpr L copyOf(const L& l) {
  return l;
}

template <typename L, typename HL = List<> >
struct Declared {
  static constexpr uint8_t size() { return L::size; }
  static constexpr uint8_t hubSize() { return HL::size; }
  DeviceName dev;
  L list;   // the device's channels
  HL hub;   // what it expects of the hub (remote.h), in declaration order
};

// The declarations of one side, in order: Pick<false, D...> the device's channels, Pick<true, D...>
// the hub channels (remote(), remoteAction(), remoteEvent()).
template <typename D>
struct IsRemote {
  static const bool value = false;
};
template <typename T, Kind K, typename C>
struct IsRemote<Decl<T, K, C> > {
  static const bool value = K >= kRemote;
};
template <bool Keep, typename H, typename L>
struct Prepend {
  typedef L type;
  static constexpr type make(const H&, const L& l) { return l; }
};
template <typename H, typename... X>
struct Prepend<true, H, List<X...> > {
  typedef List<H, X...> type;
  static constexpr type make(const H& h, const List<X...>& l) { return type{h, l}; }
};
template <bool Remote, typename... D>
struct Pick {
  static const size_t count = 0;  // a size_t: List's uint8_t size wraps at 256
  typedef List<> type;
  static constexpr type make() { return type{}; }
};
template <bool Remote, typename H, typename... R>
struct Pick<Remote, H, R...> {
  typedef Pick<Remote, R...> Rest;
  static const size_t count = Rest::count + (IsRemote<H>::value == Remote ? 1 : 0);
  typedef Prepend<IsRemote<H>::value == Remote, H, typename Rest::type> Add;
  typedef typename Add::type type;
  static constexpr type make(const H& h, const R&... r) { return Add::make(h, Rest::make(r...)); }
};

// The two lists: without hub channels (most sketches), the declarations fill the list in one
// pack expansion (brace elision: List<H, R...> is {head, tail}), so that a list of 254 does not
// copy its tails 254 times over while compiling; with them, Pick sorts them out.
template <bool Mixed, typename... D>
struct Split {
  typedef Declared<typename Pick<false, D...>::type, typename Pick<true, D...>::type> Type;
  static constexpr Type make(DeviceName dev, const D&... d) { return Type{dev, Pick<false, D...>::make(d...), Pick<true, D...>::make(d...)}; }
};
#if defined(__clang__)  // the braces are left out on purpose (brace elision), see above
#pragma clang diagnostic push
#pragma clang diagnostic ignored "-Wmissing-braces"
#endif
template <typename... D>
struct Split<false, D...> {
  typedef Declared<List<D...> > Type;
  static constexpr Type make(DeviceName dev, const D&... d) { return Type{dev, List<D...>{d..., List<>{}}, List<>{}}; }
};
#if defined(__clang__)
#pragma clang diagnostic pop
#endif

template <typename... D>
constexpr typename Split<(Pick<true, D...>::count > 0), D...>::Type declared(DeviceName dev, D... d) {
  static_assert(Pick<false, D...>::count <= HUBWIRE_MAX_CHANNELS,
                "more channels than HUBWIRE_MAX_CHANNELS: raise it (at most 254)");
  static_assert(Pick<true, D...>::count <= HUBWIRE_MAX_HUB_CHANNELS,
                "more hub channels than HUBWIRE_MAX_HUB_CHANNELS: raise it");
  return Split<(Pick<true, D...>::count > 0), D...>::make(dev, d...);
}

}  // namespace declare
}  // namespace hubwire

#endif
