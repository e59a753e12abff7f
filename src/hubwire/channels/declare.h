// Channel declarations the compiler works out: a sketch lists its channels once, at file scope,
//
//   HUBWIRE_CHANNELS(channels, "rover",
//     expose("speed", speed).writable().range(-1.0f, 1.0f).unit("m/s").failsafe(0.0f),
//     control("led", setLed),
//     event("bumper", bumper));
//
// and gets, as constants in flash, the descriptor JSON (docs/PROTOCOL.md 7) and one record per
// channel (channel.h) that the session reads when the hub addresses the channel. Nothing is built
// or checked on the board: a declaration that cannot work fails to compile, saying why.
#ifndef HUBWIRE_CHANNELS_DECLARE_H
#define HUBWIRE_CHANNELS_DECLARE_H

#include "../config.h"
#include "../session/protocol.h"
#include "../wire/types.h"
#include "channel.h"
#include "constexpr_text.h"

namespace hubwire {
namespace declare {

// The value a range or failsafe takes: the channel's scalar type, or NotNumeric where none applies.
struct NotNumeric {
  constexpr NotNumeric() {}
};
struct StructValue : NotNumeric {  // marks a struct channel: its layout text is copied to flash
  constexpr StructValue() {}
};
template <typename T>
struct IsNumeric {
  static const bool value = true;
};
template <>
struct IsNumeric<NotNumeric> {
  static const bool value = false;
};
template <>
struct IsNumeric<StructValue> {
  static const bool value = false;
};

enum Kind : uint8_t { kVariable, kControl, kAction, kEvent };

// Set while declaring when a range or failsafe value changes on its way into the channel's type
// (300 for a uint8_t, -1.5 for an int16_t); Checked<> turns it into a compile error.
const uint8_t kLossyValue = 0x80;

template <typename T>
struct IsFloat {
  static const bool value = false;
};
template <>
struct IsFloat<float> {
  static const bool value = true;
};
template <>
struct IsFloat<double> {
  static const bool value = true;
};

// A range's or failsafe's value as stored, and the comparison the session uses for it.
template <typename T>
struct Limits {
  static constexpr Scalar of(T v) { return ToScalar<T>::of(v); }
  static constexpr InRange inRange(uint8_t flags) { return flags & (kHasRange | kHasFailsafe) ? &hubwire::inRange<T> : nullptr; }
  static constexpr bool ordered(T lo, T hi) { return lo <= hi; }
  // A float channel rounds (0.1 has no exact float); an integer one must keep the value.
  template <typename U>
  static constexpr bool fits(U v) { return IsFloat<T>::value || (U)(T)v == v; }
};
template <>
struct Limits<NotNumeric> {
  static constexpr Scalar of(NotNumeric) { return Scalar(); }
  static constexpr InRange inRange(uint8_t) { return nullptr; }
  static constexpr bool ordered(NotNumeric, NotNumeric) { return true; }
  template <typename U>
  static constexpr bool fits(U) { return true; }
};
template <>
struct Limits<StructValue> : Limits<NotNumeric> {};

// ---- JSON pieces: a literal prefix, one value, a literal suffix ----
enum PieceKind : uint8_t { kNone, kInteger, kFloat, kEscaped, kLiteral, kAccessLetters, kFields };

struct Piece {
  const char* pre;
  PieceKind kind;
  int64_t integer;  // kInteger; kAccessLetters: the access bits
  float real;       // kFloat
  const char* text;  // kEscaped, kLiteral, kFields (the layout text)
  const char* post;
};
constexpr Piece literal(const char* s) { return Piece{s, kNone, 0, 0, "", ""}; }
constexpr Piece integer(const char* pre, int64_t v) { return Piece{pre, kInteger, v, 0, "", ""}; }
constexpr Piece quoted(const char* pre, const char* s) { return Piece{pre, kEscaped, 0, 0, s, "\""}; }
constexpr Piece typeNamed(const char* pre, TypeCode t);
constexpr Piece empty() { return literal(""); }

// Numbers: integers as themselves, floats (and doubles, as floats) through constexpr_text.h.
template <typename T>
constexpr Piece number(const char* pre, T v) {
  return integer(pre, (int64_t)v);
}
constexpr Piece number(const char* pre, float v) { return Piece{pre, kFloat, 0, v, "", ""}; }
constexpr Piece number(const char* pre, double v) { return Piece{pre, kFloat, 0, (float)v, "", ""}; }
constexpr Piece number(const char*, NotNumeric) { return empty(); }
constexpr Piece number(const char*, StructValue) { return empty(); }

constexpr const char* typeNameOf(TypeCode t) {
  return t == kBool ? "bool" : t == kU8 ? "u8" : t == kI8 ? "i8" : t == kU16 ? "u16" : t == kI16 ? "i16"
       : t == kU32 ? "u32" : t == kI32 ? "i32" : t == kF32 ? "f32" : t == kF64 ? "f64" : t == kStr ? "str"
       : t == kStruct ? "struct" : "void";
}
constexpr Piece typeNamed(const char* pre, TypeCode t) { return Piece{pre, kLiteral, 0, 0, typeNameOf(t), "\""}; }
constexpr size_t scalarBytes(TypeCode t) { return t == kVoid || t > kF64 ? 0 : t <= kI8 ? 1 : t <= kI16 ? 2 : t <= kF32 ? 4 : 8; }

// Access letters in the descriptor's order: r w c e s (the bits of Access, lowest first).
constexpr size_t accessLength(int64_t a) { return a ? (a & 1) + accessLength(a >> 1) : 0; }
constexpr char accessAt(int64_t a, size_t i, size_t bit = 0) {
  return (a & 1) ? (i == 0 ? "rwces"[bit] : accessAt(a >> 1, i - 1, bit + 1)) : accessAt(a >> 1, i, bit + 1);
}

// A struct layout "ax:f32,gyro:i16[3]" becomes {"n":"ax","t":"f32"},{"n":"gyro","t":"i16","c":3}:
// each character of the layout stands for a short run of JSON.
constexpr bool fieldStart(const char* s, size_t j) { return j == 0 || s[j - 1] == ','; }
constexpr const char* fieldRun(const char* s, size_t j) {  // what goes before the character itself
  return s[j] == ':' ? "\",\"t\":\"" : s[j] == '[' ? "\",\"c\":" : s[j] == ']' ? "}" : s[j] == ',' ? (s[j - 1] == ']' ? "," : "\"},")
       : fieldStart(s, j) ? "{\"n\":\"" : "";
}
constexpr bool fieldKeepsChar(char c) { return c != ':' && c != '[' && c != ']' && c != ','; }
constexpr size_t fieldLength(const char* s, size_t j) { return cx::length(fieldRun(s, j)) + (fieldKeepsChar(s[j]) ? 1 : 0); }
constexpr const char* fieldsEnd(const char* s, size_t n) { return n && s[n - 1] == ']' ? "" : "\"}"; }
constexpr size_t fieldsLength(const char* s, size_t j = 0) {
  return s[j] ? fieldLength(s, j) + fieldsLength(s, j + 1) : cx::length(fieldsEnd(s, j));
}
constexpr char fieldsAt(const char* s, size_t i, size_t j = 0) {
  return !s[j] ? fieldsEnd(s, j)[i]
       : i < fieldLength(s, j) ? (i < cx::length(fieldRun(s, j)) ? fieldRun(s, j)[i] : s[j])
                               : fieldsAt(s, i - fieldLength(s, j), j + 1);
}

// A layout's size in memory, with the alignment the board gives each field (so that it can be
// compared with sizeof the struct), or kBadLayout when the text is malformed.
const size_t kBadLayout = 0xFFFF;
constexpr bool typeNameAt(const char* s, size_t j, const char* n) {
  return *n == 0 ? (s[j] == 0 || s[j] == ',' || s[j] == '[') : s[j] == *n && typeNameAt(s, j + 1, n + 1);
}
constexpr TypeCode layoutTypeAt(const char* s, size_t j, uint8_t t = kBool) {
  return t > kF64 ? kVoid : typeNameAt(s, j, typeNameOf((TypeCode)t)) ? (TypeCode)t : layoutTypeAt(s, j, (uint8_t)(t + 1));
}
constexpr size_t colonAt(const char* s, size_t j) { return s[j] == 0 || s[j] == ':' || s[j] == ',' ? j : colonAt(s, j + 1); }
constexpr size_t digitsEnd(const char* s, size_t j) { return s[j] >= '0' && s[j] <= '9' ? digitsEnd(s, j + 1) : j; }
constexpr size_t numberIn(const char* s, size_t j, size_t end, size_t acc = 0) {
  return j == end ? acc : numberIn(s, j + 1, end, acc * 10 + (size_t)(s[j] - '0'));
}
constexpr size_t alignOfType(TypeCode t) {
  return t == kU16 || t == kI16 ? alignof(uint16_t) : t == kU32 || t == kI32 ? alignof(uint32_t)
       : t == kF32 ? alignof(float) : t == kF64 ? alignof(double) : 1;
}
constexpr size_t alignUp(size_t v, size_t a) { return (v + a - 1) / a * a; }
constexpr size_t maxOf(size_t a, size_t b) { return a > b ? a : b; }
// The field whose type name starts at t (after its colon) ends at e: a count "[n]" or nothing.
constexpr size_t countEnd(const char* s, size_t e) { return s[e] == '[' ? digitsEnd(s, e + 1) : e; }
constexpr bool countOk(const char* s, size_t e) {
  return s[e] != '[' || (s[countEnd(s, e)] == ']' && numberIn(s, e + 1, countEnd(s, e)) >= 1 &&
                         numberIn(s, e + 1, countEnd(s, e)) <= 255);
}
constexpr size_t countOf(const char* s, size_t e) { return s[e] == '[' ? numberIn(s, e + 1, countEnd(s, e)) : 1; }
constexpr size_t fieldEnd(const char* s, size_t e) { return s[e] == '[' ? countEnd(s, e) + 1 : e; }
constexpr size_t typeEnd(const char* s, size_t t) { return t + cx::length(typeNameOf(layoutTypeAt(s, t))); }
constexpr size_t layoutSizeAfter(const char* s, size_t next, size_t off, size_t maxAlign);
constexpr size_t layoutFieldSize(const char* s, size_t j, size_t off, size_t maxAlign) {
  return s[colonAt(s, j)] != ':' || colonAt(s, j) == j || layoutTypeAt(s, colonAt(s, j) + 1) == kVoid ||
                 !countOk(s, typeEnd(s, colonAt(s, j) + 1))
             ? kBadLayout
             : layoutSizeAfter(s, fieldEnd(s, typeEnd(s, colonAt(s, j) + 1)),
                               alignUp(off, alignOfType(layoutTypeAt(s, colonAt(s, j) + 1))) +
                                   scalarBytes(layoutTypeAt(s, colonAt(s, j) + 1)) * countOf(s, typeEnd(s, colonAt(s, j) + 1)),
                               maxOf(maxAlign, alignOfType(layoutTypeAt(s, colonAt(s, j) + 1))));
}
constexpr size_t layoutSizeAfter(const char* s, size_t next, size_t off, size_t maxAlign) {
  return s[next] == 0 ? alignUp(off, maxAlign)
       : s[next] == ',' && s[next + 1] != 0 ? layoutFieldSize(s, next + 1, off, maxAlign)
                                            : kBadLayout;
}
constexpr size_t layoutSize(const char* s) { return *s ? layoutFieldSize(s, 0, 0, 1) : kBadLayout; }

constexpr size_t valueLength(const Piece& p) {
  return p.kind == kInteger ? cx::integerLength(p.integer) : p.kind == kFloat ? cx::floatLength(p.real)
       : p.kind == kEscaped ? cx::escapedLength(p.text) : p.kind == kLiteral ? cx::length(p.text)
       : p.kind == kAccessLetters ? accessLength(p.integer) : p.kind == kFields ? fieldsLength(p.text) : 0;
}
constexpr char valueAt(const Piece& p, size_t i) {
  return p.kind == kInteger ? cx::integerAt(p.integer, i) : p.kind == kFloat ? cx::floatAt(p.real, i)
       : p.kind == kEscaped ? cx::escapedAt(p.text, i) : p.kind == kLiteral ? p.text[i]
       : p.kind == kAccessLetters ? accessAt(p.integer, i) : fieldsAt(p.text, i);
}
constexpr size_t pieceLength(const Piece& p) { return cx::length(p.pre) + valueLength(p) + cx::length(p.post); }
constexpr char pieceAt(const Piece& p, size_t i) {
  return i < cx::length(p.pre) ? p.pre[i]
       : i < cx::length(p.pre) + valueLength(p) ? valueAt(p, i - cx::length(p.pre))
                                                : p.post[i - cx::length(p.pre) - valueLength(p)];
}

// ---- one declaration ----
const uint8_t kPiecesPerChannel = 13;

// T: the scalar type a range or failsafe takes (NotNumeric if none). K: what was declared. Call:
// the type of the function a control or action calls, kept as itself (a constant expression cannot
// cast it to a common type) and copied to flash, where its thunk reads it.
template <typename T, Kind K, typename Call = void (*)()>
class Decl {
 public:
  // Readable by the hub; writes it sends are stored in the variable.
  constexpr Decl writable() const {
    static_assert(K == kVariable, "writable(): only a variable declared with expose() can be written by the hub");
    return Decl(*this, unit_, description_, (uint8_t)(access_ | kWritable), flags_, lo_, hi_, failsafe_, call_);
  }
  constexpr Decl streamable() const {
    static_assert(K == kVariable, "streamable(): only a variable declared with expose() can be streamed");
    return Decl(*this, unit_, description_, (uint8_t)(access_ | kStreamable), flags_, lo_, hi_, failsafe_, call_);
  }
  // Writes (a control's or action's argument) outside [min, max], any element of an array, are
  // refused with NAK OUT_OF_RANGE.
  template <typename U>
  constexpr Decl range(U min, U max) const {
    static_assert(K != kEvent, "range(): an event has no range (the sketch sets its value)");
    static_assert(K == kEvent || IsNumeric<T>::value, "range(): only a number (or an array of numbers) has a range");
    return Decl(*this, unit_, description_, access_,
                (uint8_t)(flags_ | kHasRange | (Limits<T>::fits(min) && Limits<T>::fits(max) ? 0 : kLossyValue)),
                (T)min, (T)max, failsafe_, call_);
  }
  constexpr Decl unit(const char* u) const {
    return Decl(*this, u, description_, access_, flags_, lo_, hi_, failsafe_, call_);
  }
  constexpr Decl describe(const char* d) const {
    return Decl(*this, unit_, d, access_, flags_, lo_, hi_, failsafe_, call_);
  }
  // When the link is lost the variable (every element of an array) is set to this, or the
  // control's function is called with it.
  template <typename U>
  constexpr Decl failsafe(U value) const {
    static_assert(K == kVariable || K == kControl, "failsafe(): only a variable or a control has a failsafe value");
    static_assert(!(K == kVariable || K == kControl) || IsNumeric<T>::value,
                  "failsafe(): only a number (or an array of numbers) has a failsafe value");
    return Decl(*this, unit_, description_, access_,
                (uint8_t)(flags_ | kHasFailsafe | (Limits<T>::fits(value) ? 0 : kLossyValue)), lo_, hi_, (T)value,
                call_);
  }
  // Called after the hub wrote a new value into the variable (kept where a control's function is).
  constexpr Decl onChange(void (*fn)()) const {
    static_assert(K == kVariable, "onChange(): only a variable declared with expose() has one (a control calls its function)");
    return Decl(*this, unit_, description_, access_, flags_, lo_, hi_, failsafe_, fn);
  }

  // Everything below is for HUBWIRE_CHANNELS.
  constexpr Decl(const char* name, const char* layout, void* data, TypeCode code, uint8_t count,
                 TypeCode ret, uint8_t access, Call call, Thunk thunk, uint16_t memSize = 0)
      : memSize_(memSize), name_(name), layout_(layout), unit_(nullptr), description_(nullptr), data_(data),
        call_(call), thunk_(thunk), code_(code), count_(count), ret_(ret), access_(access),
        flags_(0), lo_(), hi_(), failsafe_() {}

  // The k-th piece of this channel's JSON, as channel id.
  constexpr Piece piece(uint8_t k, uint8_t id) const {
    return k == 0 ? integer(id > 1 ? ",{\"id\":" : "{\"id\":", id)
         : k == 1 ? quoted(",\"n\":\"", name_)
         : k == 2 ? Piece{",\"a\":\"", kAccessLetters, access_, 0, "", "\""}
         : k == 3 ? typeNamed(",\"t\":\"", code_)
         : k == 4 ? (count_ ? integer(",\"c\":", count_) : empty())
         : k == 5 ? (layout_ ? Piece{",\"f\":[", kFields, 0, 0, layout_, "]"} : empty())
         : k == 6 ? (ret_ != kVoid ? typeNamed(",\"rt\":\"", ret_) : empty())
         : k == 7 ? (unit_ ? quoted(",\"u\":\"", unit_) : empty())
         : k == 8 ? (flags_ & kHasRange ? number(",\"min\":", lo_) : empty())
         : k == 9 ? (flags_ & kHasRange ? number(",\"max\":", hi_) : empty())
         : k == 10 ? (flags_ & kHasFailsafe ? number(",\"fs\":", failsafe_) : empty())
         : k == 11 ? (description_ ? quoted(",\"d\":\"", description_) : empty())
                   : literal("}");
  }
  constexpr size_t jsonLength(uint8_t id, uint8_t k = 0) const {
    return k == kPiecesPerChannel ? 0 : pieceLength(piece(k, id)) + jsonLength(id, (uint8_t)(k + 1));
  }
  constexpr char jsonAt(uint8_t id, size_t i, uint8_t k = 0) const {
    return i < pieceLength(piece(k, id)) ? pieceAt(piece(k, id), i)
                                         : jsonAt(id, i - pieceLength(piece(k, id)), (uint8_t)(k + 1));
  }
  // What the session needs at run time, given the flash copies it points to: a struct's layout
  // text and codec (named only for structs: a sketch without them links none), the function a
  // control or action calls or a variable's onChange, the range and failsafe values.
  constexpr ChannelInfo info(const char* layout, StructCodec structs, const void* call, const ChannelLimits* limits) const {
    return ChannelInfo{ValueType{code_, count_, Text(layout, true), structs}, ret_, data_, call, thunk_, limits,
                       access_, flags_};
  }
  constexpr ChannelLimits limits() const {
    return ChannelLimits{Limits<T>::inRange(flags_), Limits<T>::of(lo_), Limits<T>::of(hi_), Limits<T>::of(failsafe_)};
  }
  constexpr bool hasLimits() const { return flags_ & (kHasRange | kHasFailsafe); }
  constexpr const char* unitText() const { return unit_; }
  constexpr const char* descriptionText() const { return description_; }
  constexpr bool valuesFit() const { return !(flags_ & kLossyValue); }
  constexpr bool rangeOrdered() const { return !(flags_ & kHasRange) || Limits<T>::ordered(lo_, hi_); }
  constexpr const char* layout() const { return layout_; }
  constexpr const char* name() const { return name_; }
  constexpr Call call() const { return call_; }
  constexpr uint16_t memSize() const { return memSize_; }

 private:
  constexpr Decl(const Decl& d, const char* unit, const char* description, uint8_t access, uint8_t flags, T lo, T hi,
                 T failsafe, Call call)
      : memSize_(d.memSize_), name_(d.name_), layout_(d.layout_), unit_(unit), description_(description), data_(d.data_),
        call_(call), thunk_(d.thunk_), code_(d.code_), count_(d.count_),
        ret_(d.ret_), access_(access), flags_(flags), lo_(lo), hi_(hi), failsafe_(failsafe) {}

  uint16_t memSize_;  // structs: sizeof the struct, to check the layout against
  const char* name_;
  const char* layout_;
  const char* unit_;
  const char* description_;
  void* data_;
  Call call_;
  Thunk thunk_;
  TypeCode code_;
  uint8_t count_;
  TypeCode ret_;
  uint8_t access_;
  uint8_t flags_;
  T lo_, hi_, failsafe_;
};

// ---- the declarations ----
template <typename T, size_t Bytes>
constexpr bool checkValue() {
  static_assert(TypeOf<T>::code != kVoid, "Hubwire carries bool, 8/16/32-bit integers, float and double");
  static_assert(Bytes + kSampleHeader <= HUBWIRE_MAX_PAYLOAD, "value larger than HUBWIRE_MAX_PAYLOAD - 2: raise it");
  return true;
}
template <typename R>
constexpr bool checkReturn() {
  static_assert(TypeOf<R>::code != kVoid, "Hubwire carries bool, 8/16/32-bit integers, float and double");
  static_assert(sizeof(R) <= HUBWIRE_MAX_RETURN, "return value larger than HUBWIRE_MAX_RETURN: raise it");
  return true;
}

// A variable (scalar, fixed array, char[] string): readable; options make it writable etc.
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
// A struct with named fields, laid out by text such as "ax:f32,ay:f32,gyro:i16[3]".
template <typename T>
constexpr Decl<StructValue, kVariable> expose(const char* name, T& var, const char* layout) {
  static_assert(sizeof(T) + kSampleHeader <= HUBWIRE_MAX_PAYLOAD, "struct larger than HUBWIRE_MAX_PAYLOAD - 2: raise it");
  return Decl<StructValue, kVariable>(name, layout, &var, kStruct, 0, kVoid, kReadable, nullptr, nullptr,
                                      (uint16_t)sizeof(T));
}

// A write-only control: the hub's value is handed to fn. A bool-returning fn may refuse it.
template <typename T>
constexpr Decl<T, kControl, void (*)(T)> control(const char* name, void (*fn)(T)) {
  return checkValue<T, sizeof(T)>(), Decl<T, kControl, void (*)(T)>(name, nullptr, nullptr, TypeOf<T>::code, 0, kVoid, kWritable, fn, &callVoid<T>);
}
template <typename T>
constexpr Decl<T, kControl, bool (*)(T)> control(const char* name, bool (*fn)(T)) {
  return checkValue<T, sizeof(T)>(), Decl<T, kControl, bool (*)(T)>(name, nullptr, nullptr, TypeOf<T>::code, 0, kVoid, kWritable, fn, &callChecked<T>);
}

// A callable action: the hub calls fn with an argument and gets its return value.
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

// An event the sketch emits with emit(); the hub is told exactly once.
template <typename T>
constexpr Decl<NotNumeric, kEvent> event(const char* name, Event<T>& ev) {
  static_assert(sizeof(T) <= HUBWIRE_EVENT_MAX_PAYLOAD, "event value larger than HUBWIRE_EVENT_MAX_PAYLOAD: raise it");
  return checkValue<T, sizeof(T)>(), Decl<NotNumeric, kEvent>(name, nullptr, &ev.id, TypeOf<T>::code, 0, kVoid, kEventAccess, nullptr, nullptr);
}

// The device itself: its name and, optionally, the firmware version the hub shows.
struct DeviceName {
  constexpr DeviceName(const char* n) : name(n), firmwareText(nullptr) {}  // NOLINT: a name alone
  constexpr DeviceName(const char* n, const char* fw) : name(n), firmwareText(fw) {}
  constexpr DeviceName firmware(const char* fw) const { return DeviceName(name, fw); }
  const char* name;
  const char* firmwareText;
};
constexpr DeviceName device(const char* name) { return DeviceName(name); }

// Names as the descriptor allows them (docs/PROTOCOL.md 7): [A-Za-z_][A-Za-z0-9_]*, 1..32 long.
constexpr bool nameStart(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; }
constexpr bool nameRest(const char* s, size_t n = 1) {
  return *s == 0 ? n <= 32 : (nameStart(*s) || (*s >= '0' && *s <= '9')) && nameRest(s + 1, n + 1);
}
constexpr bool validName(const char* s) { return nameStart(*s) && nameRest(s + 1); }

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
template <typename L>
struct Declared {
  static constexpr uint8_t size() { return L::size; }
  DeviceName dev;
  L list;
};
constexpr List<> listOf() { return List<>{}; }
template <typename H, typename... R>
constexpr List<H, R...> listOf(H h, R... r) {
  return List<H, R...>{h, listOf(r...)};
}
template <typename... D>
constexpr Declared<List<D...> > declared(DeviceName dev, D... d) {
  static_assert(sizeof...(D) <= HUBWIRE_MAX_CHANNELS, "more channels than HUBWIRE_MAX_CHANNELS: raise it (at most 254)");
  return Declared<List<D...> >{dev, listOf(d...)};
}

// Texts (units, descriptions, names) are worked on by recursion, one level per character: past
// kMaxText the compiler would stop with an unclear "evaluation depth" error, so they are checked
// first, four characters a level.
const size_t kMaxText = 255;
constexpr bool shortText(const char* s, size_t n = 0) {
  return !s || n > kMaxText ? !s : !s[n] || !s[n + 1] || !s[n + 2] || !s[n + 3] || shortText(s, n + 4);
}
template <typename T, Kind K, typename C>
constexpr bool textsShort(const Decl<T, K, C>& d) {
  return shortText(d.name()) && shortText(d.unitText()) && shortText(d.descriptionText()) && shortText(d.layout());
}
constexpr bool allTextsShort(const List<>&) { return true; }
template <typename H, typename... R>
constexpr bool allTextsShort(const List<H, R...>& l) {
  return textsShort(l.head) && allTextsShort(l.tail);
}

// Is no channel in l called name? Are all names in l different?
constexpr bool noneNamed(const List<>&, const char*) { return true; }
template <typename H, typename... R>
constexpr bool noneNamed(const List<H, R...>& l, const char* name) {
  return !cx::equal(l.head.name(), name) && noneNamed(l.tail, name);
}
constexpr bool namesUnique(const List<>&) { return true; }
template <typename H, typename... R>
constexpr bool namesUnique(const List<H, R...>& l) {
  return noneNamed(l.tail, l.head.name()) && namesUnique(l.tail);
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

template <typename D, const D* Decls, typename S>
struct Channels;
template <typename D, const D* Decls>
struct Channels<D, Decls, cx::Seq<> > {
  Chars<TailPart> tail;
  static constexpr Channels make() { return Channels{Chars<TailPart>::make()}; }
};
template <typename D, const D* Decls, size_t I, size_t... R>
struct Channels<D, Decls, cx::Seq<I, R...> > {
  Chars<ChannelPart<D, Decls, I> > first;
  Channels<D, Decls, cx::Seq<R...> > rest;
  static constexpr Channels make() {
    return Channels{Chars<ChannelPart<D, Decls, I> >::make(), Channels<D, Decls, cx::Seq<R...> >::make()};
  }
};
template <typename D, const D* Decls>
struct JsonText {
  Chars<HeadPart<D, Decls> > head;
  Channels<D, Decls, typename cx::MakeSeq<D::size()>::type> body;
};
// value is constexpr where it is declared (the hash reads it while compiling), so it is a member of
// a class of its own: a class cannot hold a constexpr object of its own, still incomplete, type.
template <typename D, const D* Decls>
struct Json {
  typedef JsonText<D, Decls> Text;
  static constexpr Text value = {Chars<HeadPart<D, Decls> >::make(), decltype(Text::body)::make()};
};
template <typename D, const D* Decls>
constexpr typename Json<D, Decls>::Text Json<D, Decls>::value HUBWIRE_FLASH;

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
template <typename D, const D* Decls>
constexpr uint32_t hashOf(const Channels<D, Decls, cx::Seq<> >& b, uint32_t h) {
  return fnvChars(b.tail.c, sizeof(b.tail.c), h);
}
template <typename D, const D* Decls, size_t I, size_t... R>
constexpr uint32_t hashOf(const Channels<D, Decls, cx::Seq<I, R...> >& b, uint32_t h) {
  return hashOf(b.rest, fnvChars(b.first.c, sizeof(b.first.c), h));
}

// A struct channel's layout text, copied into flash for the session's struct codec.
template <typename D, const D* Decls, size_t I>
struct LayoutPart {
  static constexpr size_t length() { return cx::length(DeclAt<D, Decls, I>::decl.layout()) + 1; }
  static constexpr char at(size_t i) { return DeclAt<D, Decls, I>::decl.layout()[i]; }
};
template <typename D, const D* Decls, size_t I>
struct LayoutFlash {
  static const Chars<LayoutPart<D, Decls, I> > value;
};
template <typename D, const D* Decls, size_t I>
const Chars<LayoutPart<D, Decls, I> > LayoutFlash<D, Decls, I>::value HUBWIRE_FLASH = Chars<LayoutPart<D, Decls, I> >::make();

// The function a control or action calls (or a variable's onChange), kept in flash with its own type.
template <typename D, const D* Decls, size_t I>
struct CallFlash {
  typedef decltype(DeclAt<D, Decls, I>::decl.call()) Fn;
  static const Fn value;
};
template <typename D, const D* Decls, size_t I>
const typename CallFlash<D, Decls, I>::Fn CallFlash<D, Decls, I>::value HUBWIRE_FLASH = DeclAt<D, Decls, I>::decl.call();

// A channel's range and failsafe values, in flash only for channels that declare them.
template <typename D, const D* Decls, size_t I>
struct LimitsFlash {
  static const ChannelLimits value;
};
template <typename D, const D* Decls, size_t I>
const ChannelLimits LimitsFlash<D, Decls, I>::value HUBWIRE_FLASH = DeclAt<D, Decls, I>::decl.limits();

template <typename T, Kind K, typename C>
constexpr bool isStruct(const Decl<T, K, C>*) { return false; }
template <Kind K, typename C>
constexpr bool isStruct(const Decl<StructValue, K, C>*) { return true; }

// What is checked of every channel (the compiler's message names the channel's index I, from 0).
template <typename D, const D* Decls, size_t I>
struct Checked {
  static_assert(validName(DeclAt<D, Decls, I>::decl.name()),
                "channel name: letters, digits and _ only, not starting with a digit, at most 32 characters");
  static_assert(DeclAt<D, Decls, I>::decl.rangeOrdered(), "range(min, max): min is greater than max");
  static_assert(DeclAt<D, Decls, I>::decl.valuesFit(),
                "range() or failsafe(): a value the channel's type cannot hold (e.g. 300 for a uint8_t, 1.5 for an int)");
};

// The flash copies a record points to, each instantiated (and so kept) only where it applies.
template <typename D, const D* Decls, size_t I, bool IsStruct = isStruct((typename DeclAt<D, Decls, I>::Type*)nullptr)>
struct StructOf {
  static constexpr const char* layout() { return nullptr; }
  static constexpr StructCodec codec() { return nullptr; }
};
template <typename D, const D* Decls, size_t I>
struct StructOf<D, Decls, I, true> {
  static_assert(layoutSize(DeclAt<D, Decls, I>::decl.layout()) == DeclAt<D, Decls, I>::decl.memSize(),
                "struct layout does not match the struct: name:type[count] for every field, in order, "
                "types bool u8 i8 u16 i16 u32 i32 f32 f64 (e.g. \"ax:f32,gyro:i16[3]\")");
  static constexpr const char* layout() { return LayoutFlash<D, Decls, I>::value.c; }
  static constexpr StructCodec codec() { return &structCodec; }
};
template <typename D, const D* Decls, size_t I, bool HasCall = DeclAt<D, Decls, I>::decl.call() != nullptr>
struct CallOf {
  static constexpr const void* get() { return nullptr; }
};
template <typename D, const D* Decls, size_t I>
struct CallOf<D, Decls, I, true> {
  static constexpr const void* get() { return &CallFlash<D, Decls, I>::value; }
};
template <typename D, const D* Decls, size_t I, bool HasLimits = DeclAt<D, Decls, I>::decl.hasLimits()>
struct LimitsOf {
  static constexpr const ChannelLimits* get() { return nullptr; }
};
template <typename D, const D* Decls, size_t I>
struct LimitsOf<D, Decls, I, true> {
  static constexpr const ChannelLimits* get() { return &LimitsFlash<D, Decls, I>::value; }
};

template <typename D, const D* Decls, size_t I>
struct InfoOf : Checked<D, Decls, I> {
  static constexpr ChannelInfo make() {
    return DeclAt<D, Decls, I>::decl.info(StructOf<D, Decls, I>::layout(), StructOf<D, Decls, I>::codec(),
                                       CallOf<D, Decls, I>::get(), LimitsOf<D, Decls, I>::get());
  }
};

template <typename D, const D* Decls, typename S = typename cx::MakeSeq<D::size()>::type>
struct Infos;
template <typename D, const D* Decls, size_t... I>
struct Infos<D, Decls, cx::Seq<I...> > {
  static const ChannelInfo value[sizeof...(I) ? sizeof...(I) : 1];
};
template <typename D, const D* Decls, size_t... I>
const ChannelInfo Infos<D, Decls, cx::Seq<I...> >::value[sizeof...(I) ? sizeof...(I) : 1] HUBWIRE_FLASH = {
    InfoOf<D, Decls, I>::make()...};

template <typename D, const D* Decls>
constexpr ChannelTable table() {
  static_assert(allTextsShort(Decls->list) && shortText(Decls->dev.name) && shortText(Decls->dev.firmwareText),
                "a name, unit, description, layout or firmware text longer than 255 characters");
  static_assert(namesUnique(Decls->list), "two channels have the same name");
  static_assert(sizeof(JsonText<D, Decls>) <= kMaxDescriptor, "descriptor longer than the 16 KiB a hub accepts");
  return ChannelTable{Json<D, Decls>::value.head.c, (uint16_t)sizeof(JsonText<D, Decls>),
                      hashOf(Json<D, Decls>::value.body,
                             fnvChars(Json<D, Decls>::value.head.c, sizeof(Json<D, Decls>::value.head.c), kFnvOffset)),
                      Infos<D, Decls>::value,
                      D::size()};
}

}  // namespace declare
}  // namespace hubwire

// Declares a sketch's channels at file scope; `var` is then what begin() takes. Between the device
// and its channels: expose(), control(), action() and event() (see above), with their options.
#define HUBWIRE_CHANNELS(var, deviceName, ...)                                                     \
  namespace hubwire_channels_##var {                                                               \
  using namespace ::hubwire::declare;                                                              \
  constexpr auto declared = ::hubwire::declare::declared(deviceName, __VA_ARGS__);                 \
  }                                                                                                \
  constexpr ::hubwire::ChannelTable var HUBWIRE_FLASH =                                            \
      ::hubwire::declare::table<decltype(hubwire_channels_##var::declared), &hubwire_channels_##var::declared>()

#endif
