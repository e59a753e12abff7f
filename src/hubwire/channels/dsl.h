// The declaration DSL a sketch writes inside HUBWIRE_CHANNELS (declare.h): expose(), control(),
// action(), event() and device(), each a constexpr Decl whose options (writable(), range(),
// unit(), failsafe() ...) return a changed copy; a declaration that cannot work fails to compile
// here, saying why. declared() gathers them into a list for tables.h.
#ifndef HUBWIRE_CHANNELS_DSL_H
#define HUBWIRE_CHANNELS_DSL_H

#include <stddef.h>
#include <stdint.h>

#include "../config.h"
#include "../wire/messages.h"
#include "../wire/values.h"
#include "channel.h"
#include "../features.h"
#include "json.h"

namespace hubwire {
namespace declare {

// The value a range or failsafe takes: the channel's scalar type, or NotNumeric where none applies.
struct NotNumeric {
  constexpr NotNumeric() {}
};
struct StructValue : NotNumeric {  // marks a struct channel: its compiled layout is kept in flash
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

// kRemote...: what the sketch expects of the hub (remote.h), listed under "hub" in the descriptor.
// kMission: a long action (mission.h).
enum Kind : uint8_t { kVariable, kControl, kAction, kEvent, kMission, kRemote, kRemoteAction, kRemoteEvent };

// Set while declaring when a range or failsafe value changes on its way into the channel's type
// (300 for a uint8_t, -1.5 for an int16_t); Checked<> turns it into a compile error.
const uint8_t kLossyValue = 0x80;
// Set by onChange(): whether a function is called is known from the declaration alone, so the
// function may be declared before HUBWIRE_CHANNELS and defined after it (GCC 5 cannot compare the
// address of a function not yet defined with nullptr while compiling).
const uint8_t kOnChangeGiven = 0x40;
// Set by progressMax() (a mission's "pmax").
const uint8_t kHasProgressMax = 0x20;

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

// A range or failsafe a channel does not have writes nothing.
constexpr Piece number(const char*, NotNumeric) { return empty(); }
constexpr Piece number(const char*, StructValue) { return empty(); }

// ---- one declaration ----
const uint8_t kPiecesPerChannel = 16;

// T: the scalar type a range or failsafe takes (NotNumeric if none). K: what was declared. Call:
// the type of the function a control or action calls, kept as itself (a constant expression cannot
// cast it to a common type) and copied to flash, where its thunk reads it.
template <typename T, Kind K, typename Call = void (*)()>
class Decl {
  template <typename, Kind, typename>
  friend class Decl;

 public:
  /// Readable and writable by the hub; writes it sends are stored in the variable.
  ///   expose("speed", speed).writable()
  constexpr Decl writable() const {
    static_assert(K == kVariable || K == kRemote,
                  "writable(): only a variable declared with expose() can be written by the hub (or remote(), by the sketch)");
    return Decl(*this, unit_, description_, (uint8_t)(access_ | kWritable), flags_, lo_, hi_, failsafe_, call_);
  }
  /// The hub may subscribe to samples of it at an interval.
  ///   expose("battery", batteryMv).streamable()
  constexpr Decl streamable() const {
    static_assert(K == kVariable, "streamable(): only a variable declared with expose() can be streamed");
    return Decl(*this, unit_, description_, (uint8_t)(access_ | kStreamable), flags_, lo_, hi_, failsafe_, call_);
  }
  /// Writes (a control's or action's argument) outside [min, max], any element of an array, are
  /// refused with NAK OUT_OF_RANGE.
  ///   expose("speed", speed).writable().range(-1.0f, 1.0f)
  template <typename U>
  constexpr Decl range(U min, U max) const {
    static_assert(K != kEvent, "range(): an event has no range (the sketch sets its value)");
    static_assert(K == kEvent || IsNumeric<T>::value, "range(): only a number (or an array of numbers) has a range");
    return Decl(*this, unit_, description_, access_,
                (uint8_t)(flags_ | kHasRange | (Limits<T>::fits(min) && Limits<T>::fits(max) ? 0 : kLossyValue)),
                (T)min, (T)max, failsafe_, call_);
  }
  /// The unit the hub shows.
  ///   expose("range", rangeCm).unit("cm")
  constexpr Decl unit(const char* u) const {
    return Decl(*this, u, description_, access_, flags_, lo_, hi_, failsafe_, call_);
  }
  /// A description the hub shows.
  ///   action("beep", beep).describe("beep for ms (max 2000)")
  constexpr Decl describe(const char* d) const {
    return Decl(*this, unit_, d, access_, flags_, lo_, hi_, failsafe_, call_);
  }
  /// When the link is lost the variable (every element of an array) is set to this, or the
  /// control's function is called with it.
  ///   expose("left", left).writable().failsafe(0.0f)
  template <typename U>
  constexpr Decl failsafe(U value) const {
    static_assert(K != kMission, "failsafe(): a mission has no failsafe value (stop it in the sketch's onLinkLost())");
    static_assert(K == kVariable || K == kControl || K == kMission, "failsafe(): only a variable or a control has a failsafe value");
    static_assert(!(K == kVariable || K == kControl) || IsNumeric<T>::value,
                  "failsafe(): only a number (or an array of numbers) has a failsafe value");
    return Decl(*this, unit_, description_, access_,
                (uint8_t)(flags_ | kHasFailsafe | (Limits<T>::fits(value) ? 0 : kLossyValue)), lo_, hi_, (T)value,
                call_);
  }
  /// Called after the hub wrote a new value into the variable (kept where a control's function is).
  ///   expose("led", led).writable().onChange(ledChanged)
  constexpr Decl onChange(void (*fn)()) const {
    static_assert(K == kVariable || K == kRemoteEvent,
                  "onChange(): only a variable declared with expose() has one (a control calls its function), or remoteEvent()");
    return Decl(*this, unit_, description_, access_, (uint8_t)(flags_ | kOnChangeGiven), lo_, hi_, failsafe_, fn);
  }

  /// A mission's progress value at completion (the hub draws a bar from 0 to it; informative).
  ///   mission("drive", drive, startDrive, cancelDrive).progressMax(2.0f)
  constexpr Decl progressMax(float max) const {
    static_assert(K == kMission, "progressMax(): only a mission has progress");
    return Decl(*this, max);
  }

  /// A hub value the sketch only writes (never requests).
  ///   remote("report", report).writeOnly()
  constexpr Decl writeOnly() const {
    static_assert(K == kRemote, "writeOnly(): only a hub value declared with remote()");
    return Decl(*this, unit_, description_, kWritable, flags_, lo_, hi_, failsafe_, call_);
  }

  // Everything below is for HUBWIRE_CHANNELS.
  // The same declaration as another kind (remote.h: remote() is expose() for the hub's side).
  template <Kind K2>
  constexpr Decl<T, K2, Call> as(uint8_t access) const {
    return Decl<T, K2, Call>(name_, layout_, data_, code_, count_, ret_, access, call_, thunk_, memSize_, retCount_);
  }
  constexpr Decl(const char* name, const char* layout, void* data, TypeCode code, uint8_t count,
                 TypeCode ret, uint8_t access, Call call, Thunk thunk, uint16_t memSize = 0, uint8_t retCount = 0,
                 TypeCode progress = kVoid)
      : memSize_(memSize), retCount_(retCount), progress_(progress), progressMax_(0), name_(name), layout_(layout),
        unit_(nullptr), description_(nullptr), data_(data),
        call_(call), thunk_(thunk), code_(code), count_(count), ret_(ret), access_(access),
        flags_(0), lo_(), hi_(), failsafe_() {}

  // The k-th piece of this channel's JSON, as channel id.
  constexpr Piece piece(uint8_t k, uint8_t id) const {
    return k == 0 ? integer(id > 1 ? ",{\"id\":" : "{\"id\":", id)
         : k == 1 ? quoted(",\"n\":\"", name_)
         : k == 2 ? Piece{",\"a\":\"", kAccessLetters, access_, 0, "", "\""}
         : k == 3 ? typeNamed(",\"t\":\"", elementOf(code_))
         : k == 4 ? (count_ ? integer(isListCode(code_) ? ",\"vc\":" : ",\"c\":", count_) : empty())
         : k == 5 ? (layout_ ? Piece{",\"f\":[", kFields, 0, 0, layout_, "]"} : empty())
         : k == 6 ? (ret_ != kVoid ? typeNamed(",\"rt\":\"", elementOf(ret_)) : empty())
         : k == 7 ? (progress_ != kVoid ? typeNamed(",\"pt\":\"", progress_) : empty())
         : k == 8 ? (flags_ & kHasProgressMax ? number(",\"pmax\":", progressMax_) : empty())
         : k == 9 ? (unit_ ? quoted(",\"u\":\"", unit_) : empty())
         : k == 10 ? (flags_ & kHasRange ? number(",\"min\":", lo_) : empty())
         : k == 11 ? (flags_ & kHasRange ? number(",\"max\":", hi_) : empty())
         : k == 12 ? (flags_ & kHasFailsafe ? number(",\"fs\":", failsafe_) : empty())
         : k == 13 ? (description_ ? quoted(",\"d\":\"", description_) : empty())
         : k == 14 ? (retCount_ ? integer(",\"rvc\":", retCount_) : empty())
                   : literal("}");  // k == 15
  }
  constexpr size_t jsonLength(uint8_t id, uint8_t k = 0) const {
    return k == kPiecesPerChannel ? 0 : pieceLength(piece(k, id)) + jsonLength(id, (uint8_t)(k + 1));
  }
  constexpr char jsonAt(uint8_t id, size_t i, uint8_t k = 0) const {
    return i < pieceLength(piece(k, id)) ? pieceAt(piece(k, id), i)
                                         : jsonAt(id, i - pieceLength(piece(k, id)), (uint8_t)(k + 1));
  }
  // What the session needs at run time, given the flash copies it points to: a struct's compiled
  // layout, the function a
  // control or action calls or a variable's onChange, the range and failsafe values.
  constexpr ChannelInfo info(const char* layout, const void* call, const ChannelLimits* limits) const {
    return ChannelInfo{ValueType{code_, count_, layout}, ret_, data_, call, thunk_, limits,
                       access_, (uint8_t)(flags_ & (kHasRange | kHasFailsafe))};
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
  // Does the session call a function for this channel: a control's or action's, or onChange()'s?
  constexpr bool hasCall() const { return K == kControl || K == kAction || K == kMission || (flags_ & kOnChangeGiven); }
  constexpr bool isMission() const { return K == kMission; }
  constexpr uint16_t memSize() const { return memSize_; }
  // Bytes of the value on the wire at most (a list or string full), 0 for none.
  constexpr uint16_t wireBytes() const {
    return (uint16_t)(code_ == kStr ? 1 + count_
                      : code_ == kStruct ? (layoutSize(layout_) == kBadLayout ? 0 : layoutWireSize(layout_))
                      : isListCode(code_) ? 1 + count_ * scalarBytes(elementOf(code_))
                                          : scalarBytes(code_) * (count_ ? count_ : 1));
  }
  // Does a message carrying the value (a sample: 2 bytes more) not fit the device's frame?
  constexpr bool large() const { return K < kRemote && wireBytes() + kSampleHeader > HUBWIRE_MAX_PAYLOAD; }
  // The bytes a write or call with this value needs reassembled (0: it fits one frame).
  constexpr uint16_t largeIn() const {
    return (K == kControl || K == kAction || (K == kVariable && (access_ & kWritable))) && wireBytes() > HUBWIRE_MAX_PAYLOAD
               ? wireBytes()
               : 0;
  }
  constexpr bool listWithFailsafe() const { return isListCode(code_) && (flags_ & kHasFailsafe); }
  // The session's features this channel needs (features.h).
  constexpr uint16_t features() const {
    return (uint16_t)((access_ & kStreamable ? kUsesStreams : 0) | (flags_ & kHasFailsafe ? kUsesFailsafes : 0) |
                      (code_ == kStr ? kUsesStrings : 0) | (code_ == kStruct ? kUsesStructs : 0) |
                      (K == kControl || K == kAction ? kUsesCalls : 0) | (ret_ != kVoid && K != kMission ? kUsesReturns : 0) |
                      (isListCode(ret_) ? kUsesLists : 0) | (K == kMission ? kUsesMissions : 0) |
                      (K == kEvent ? kUsesEvents : 0) | (flags_ & kHasRange ? kUsesRanges : 0) |
                      (access_ & kWritable && K == kVariable ? kUsesWrites : 0) | (access_ & kReadable ? kUsesReads : 0) |
                      (isListCode(code_) ? kUsesLists : 0) | (large() ? kUsesLarge : 0));
  }

 private:
  constexpr Decl(const Decl& d, const char* unit, const char* description, uint8_t access, uint8_t flags, T lo, T hi,
                 T failsafe, Call call)
      : memSize_(d.memSize_), retCount_(d.retCount_), progress_(d.progress_), progressMax_(d.progressMax_), name_(d.name_),
        layout_(d.layout_), unit_(unit), description_(description), data_(d.data_),
        call_(call), thunk_(d.thunk_), code_(d.code_), count_(d.count_),
        ret_(d.ret_), access_(access), flags_(flags), lo_(lo), hi_(hi), failsafe_(failsafe) {}
  constexpr Decl(const Decl& d, float progressMax)
      : memSize_(d.memSize_), retCount_(d.retCount_), progress_(d.progress_), progressMax_(progressMax), name_(d.name_),
        layout_(d.layout_),
        unit_(d.unit_), description_(d.description_), data_(d.data_), call_(d.call_), thunk_(d.thunk_), code_(d.code_),
        count_(d.count_), ret_(d.ret_), access_(d.access_), flags_((uint8_t)(d.flags_ | kHasProgressMax)), lo_(d.lo_),
        hi_(d.hi_), failsafe_(d.failsafe_) {}

  uint16_t memSize_;  // structs: sizeof the struct, to check the layout against
  uint8_t retCount_;  // an action returning a List: its capacity ("rvc")
  TypeCode progress_;  // missions: the progress value's type
  float progressMax_;  // missions: progressMax()
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

template <typename... D>
constexpr Declared<typename Pick<false, D...>::type, typename Pick<true, D...>::type> declared(DeviceName dev, D... d) {
  static_assert(Pick<false, D...>::count <= HUBWIRE_MAX_CHANNELS,
                "more channels than HUBWIRE_MAX_CHANNELS: raise it (at most 254)");
  static_assert(Pick<true, D...>::count <= HUBWIRE_MAX_HUB_CHANNELS,
                "more hub channels than HUBWIRE_MAX_HUB_CHANNELS: raise it");
  return Declared<typename Pick<false, D...>::type, typename Pick<true, D...>::type>{
      dev, Pick<false, D...>::make(d...), Pick<true, D...>::make(d...)};
}

}  // namespace declare
}  // namespace hubwire

#endif
