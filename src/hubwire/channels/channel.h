// What the session knows about a channel at run time: one ChannelInfo per channel, a constant in
// flash that the compiler worked out from the sketch's declarations (declare.h). A channel costs
// no RAM on the boards HUBWIRE_FLASH covers (text.h: AVR, Teensy 4, and those that keep constants in
// flash); the session copies its record onto the stack while it handles a frame for it.
#ifndef HUBWIRE_CHANNELS_CHANNEL_H
#define HUBWIRE_CHANNELS_CHANNEL_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "../config.h"
#include "../text.h"
#include "../wire/values.h"

namespace hubwire {

enum Access : uint8_t {
  kReadable = 1,
  kWritable = 2,
  kCallable = 4,
  kEventAccess = 8,
  kStreamable = 16,
  kMissionAccess = 32,  // a mission (session/missions.h): started, cancelled and read with its own ops
};
enum ChannelFlags : uint8_t { kHasRange = 1, kHasFailsafe = 2 };

// A declared event: keep one per event (a global), emit with Session::emit().
template <typename T>
struct Event {
  uint8_t id;  // set by begin()
};

// An action of the hub the sketch calls (remoteAction(), Session::call()), by its signature:
//   hubwire::RemoteAction<bool(float)> dock;   // takes a float, returns a bool
template <typename Signature>
struct RemoteAction;
template <typename R, typename A>
struct RemoteAction<R(A)> {
  uint8_t unused;  // a handle: only its address counts
};
template <typename R>
struct RemoteAction<R()> {
  uint8_t unused;
};

// Calls the function a control or action declared, with a typed argument and return value, both as
// little-endian bytes. call points to that function's pointer, kept in flash with its own type.
// Returns false when the function refused the value (controls returning bool).
typedef bool (*Thunk)(const void* call, const uint8_t* arg, uint8_t* ret);

template <typename F>
F functionAt(const void* call) {
  return flashRead(static_cast<const F*>(call));
}
template <typename T>
bool callVoid(const void* call, const uint8_t* arg, uint8_t*) {
  T a;
  memcpy(&a, arg, sizeof(T));
  functionAt<void (*)(T)>(call)(a);
  return true;
}
template <typename T>
bool callChecked(const void* call, const uint8_t* arg, uint8_t*) {
  T a;
  memcpy(&a, arg, sizeof(T));
  return functionAt<bool (*)(T)>(call)(a);
}
template <typename R, typename A>
bool callRet(const void* call, const uint8_t* arg, uint8_t* ret) {
  A a;
  memcpy(&a, arg, sizeof(A));
  R r = functionAt<R (*)(A)>(call)(a);
  memcpy(ret, &r, sizeof(R));
  return true;
}
template <typename R>
bool callNoArg(const void* call, const uint8_t*, uint8_t* ret) {
  R r = functionAt<R (*)()>(call)();
  memcpy(ret, &r, sizeof(R));
  return true;
}
// A List argument arrives in its wire form (count, then packed elements).
template <typename L>
void listFromWire(L& a, const uint8_t* arg) {
  a.count = arg[0];
  memcpy(a.items, arg + 1, arg[0] * sizeof(a.items[0]));
}
template <typename L>
bool callListVoid(const void* call, const uint8_t* arg, uint8_t*) {
  L a;
  listFromWire(a, arg);
  functionAt<void (*)(const L&)>(call)(a);
  return true;
}
template <typename L>
bool callListChecked(const void* call, const uint8_t* arg, uint8_t*) {
  L a;
  listFromWire(a, arg);
  return functionAt<bool (*)(const L&)>(call)(a);
}
template <typename R, typename L>
bool callListRet(const void* call, const uint8_t* arg, uint8_t* ret) {
  L a;
  listFromWire(a, arg);
  R r = functionAt<R (*)(const L&)>(call)(a);
  memcpy(ret, &r, sizeof(R));
  return true;
}
// A returned List goes out in its wire form (count, then packed elements).
template <typename L>
void listToWire(const L& r, uint8_t* ret) {
  ret[0] = r.count < L::capacity() ? r.count : L::capacity();
  memcpy(ret + 1, r.items, ret[0] * sizeof(r.items[0]));
}
template <typename L, typename A>
bool callRetList(const void* call, const uint8_t* arg, uint8_t* ret) {
  A a;
  memcpy(&a, arg, sizeof(A));
  listToWire(functionAt<L (*)(A)>(call)(a), ret);
  return true;
}
template <typename L>
bool callNoArgList(const void* call, const uint8_t*, uint8_t* ret) {
  listToWire(functionAt<L (*)()>(call)(), ret);
  return true;
}
inline bool callPlain(const void* call, const uint8_t*, uint8_t*) {
  functionAt<void (*)()>(call)();
  return true;
}

// One scalar of the channel's own type (a range limit or a failsafe value), its bytes at the start
// (little-endian, config.h): integers are stored widened, floats as themselves.
#if HUBWIRE_HAS_F64
typedef uint64_t ScalarBits;
#else
typedef uint32_t ScalarBits;
#endif
union Scalar {
  struct Bits {};
  Scalar() = default;  // trivial: a Scalar about to be overwritten is not zeroed first; Scalar() is zero
  constexpr Scalar(Bits, ScalarBits b) : bits(b) {}
  constexpr Scalar(float v) : f32(v) {}  // NOLINT
#if HUBWIRE_HAS_F64
  constexpr Scalar(double v) : f64(v) {}  // NOLINT
#endif
  ScalarBits bits;
  float f32;
#if HUBWIRE_HAS_F64
  double f64;
#endif
};
// of(): a failsafe value; bound(): a range limit, as inRange<T> reads it.
template <typename T>
struct ToScalar {
  static constexpr Scalar of(T v) { return Scalar(Scalar::Bits(), (ScalarBits)(int64_t)v); }
  static constexpr Scalar bound(T v) { return of(v); }
};
// A float's bits order as a sign and a magnitude, so float ranges are judged on integer keys, without
// the soft-float comparison boards without an FPU would link for them: the limits' keys are worked
// out by the compiler (exactly: scaling by 2 is exact), the value's at run time (inRange<float>).
// -0 and +0 share key 0. Limits are never NaN (range() refuses a min and max that do not compare),
// so a NaN's key lies beyond one of them: NaN fails, as with float comparison.
constexpr int f32Exponent(float a, int e) {
  return a >= 2.0f ? f32Exponent(a / 2.0f, e + 1) : a < 1.0f && e > -126 ? f32Exponent(a * 2.0f, e - 1) : e;
}
constexpr float f32Scaled(float a, int e) {  // a scaled into [1, 2), or below 1 for a subnormal
  return a >= 2.0f ? f32Scaled(a / 2.0f, e + 1) : a < 1.0f && e > -126 ? f32Scaled(a * 2.0f, e - 1) : a;
}
constexpr uint32_t f32Magnitude(float a) {  // a >= 0
  return a > 3.40282347e38f ? 0x7F800000u
       : a == 0.0f          ? 0u
       : f32Scaled(a, 0) >= 1.0f
           ? ((uint32_t)(f32Exponent(a, 0) + 127) << 23) | (uint32_t)((f32Scaled(a, 0) - 1.0f) * 8388608.0f)
           : (uint32_t)(f32Scaled(a, 0) * 8388608.0f);
}
constexpr int32_t f32Key(float v) { return v < 0.0f ? -(int32_t)f32Magnitude(-v) : (int32_t)f32Magnitude(v); }

template <>
struct ToScalar<float> {
  static constexpr Scalar of(float v) { return Scalar(v); }
  static constexpr Scalar bound(float v) { return Scalar(Scalar::Bits(), (ScalarBits)(uint32_t)f32Key(v)); }
};
template <>
struct ToScalar<double> {
#if HUBWIRE_HAS_F64
  static constexpr Scalar of(double v) { return Scalar(v); }
#else
  static constexpr Scalar of(double v) { return Scalar((float)v); }  // double is float here
#endif
  static constexpr Scalar bound(double v) { return of(v); }
};

// Is the value at v (the channel's type) within [*lo, *hi]? Instantiated only for types given a
// range or failsafe: a sketch without float ranges links no float comparison.
typedef bool (*InRange)(const void* v, const Scalar* lo, const Scalar* hi);
template <typename T>
bool inRange(const void* v, const Scalar* lo, const Scalar* hi) {
  T x, a, b;
  memcpy(&x, v, sizeof(T));
  memcpy(&a, lo, sizeof(T));
  memcpy(&b, hi, sizeof(T));
  return x >= a && x <= b;  // NaN fails
}
template <>
inline bool inRange<float>(const void* v, const Scalar* lo, const Scalar* hi) {
  static_assert(sizeof(float) == 4, "IEEE single precision");
  int32_t b, a, c;
  memcpy(&b, v, 4);
  memcpy(&a, lo, 4);  // keys (ToScalar<float>::bound)
  memcpy(&c, hi, 4);
  int32_t x = b < 0 ? -(b & 0x7FFFFFFF) : b;
  return x >= a && x <= c;
}
// A channel's range and failsafe values (ChannelInfo::flags says which it has), in flash apart
// from its record: only channels that declare them pay for them.
struct ChannelLimits {
  InRange inRange;  // their type's comparison
  Scalar min, max, failsafe;
};

struct ChannelInfo {
  ValueType type;    // value, call argument, or event value
  TypeCode ret;      // callables: return value (a scalar)
  void* data;        // the variable behind a readable/writable channel; events: the handle's id
  const void* call;  // the function a control or action calls, or a variable's onChange (in flash, see Thunk)
  Thunk thunk;       // how to call a control or action
  const ChannelLimits* limits;  // in flash; nullptr without range and failsafe
  uint8_t access;
  uint8_t flags;
};

// A sketch's declarations as begin() takes them (HUBWIRE_CHANNELS): the descriptor JSON and one
// record per channel, all in flash.
struct ChannelTable {
  const char* json;  // in flash, after hello's fixed fields and the first kDigestSize bytes of its SHA-256
  uint32_t hash;  // FNV-1a of the JSON, worked out by the compiler as well
  uint16_t jsonLength;
  const ChannelInfo* channels;
  uint8_t count;
};

// The sketch's one table as a constant the whole program sees, and where its flash copy is (the
// one begin() takes): HUBWIRE_CHANNELS defines both (declare.h), and with link-time optimisation
// the session's reads of the table become immediates, so the table takes no RAM. A program with
// several tables (HUBWIRE_ALL_FEATURES, features.h) gets the library's weak defaults, count 0
// (features.cpp): there the session keeps a pointer to the table begin() was given. (count, not
// json, tells the two apart: avr-gcc does not fold an address's test against null.)
extern const ChannelTable sketchTable;
extern const ChannelTable* const sketchTableAt;

}  // namespace hubwire

#endif
