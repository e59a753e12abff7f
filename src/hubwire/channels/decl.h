// One declaration of the DSL (dsl.h): class Decl, a constexpr value holding what a sketch declared of
// a channel (name, type, access, options) and writing its descriptor entry; each option returns a
// changed copy, and an option that cannot apply fails to compile here, saying why.
#ifndef HUBWIRE_CHANNELS_DECL_H
#define HUBWIRE_CHANNELS_DECL_H

#include <stddef.h>
#include <stdint.h>

#include "../config.h"
#include "../wire/messages.h"
#include "../wire/values.h"
#include "channel.h"
#include "../features.h"
#include "json.h"
#include "mistakes.h"

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

// x < 0 written so that an unsigned X draws no "always false" warning.
template <typename X>
constexpr bool negative(X x) { return !(x > 0) && !(x == 0); }

// A range's or failsafe's value as stored, and the comparison the session uses for it.
template <typename T>
struct Limits {
  static constexpr Scalar of(T v) { return ToScalar<T>::of(v); }
  static constexpr Scalar bound(T v) { return ToScalar<T>::bound(v); }
  static constexpr InRange inRange(uint8_t flags) { return flags & (kHasRange | kHasFailsafe) ? &hubwire::inRange<T> : nullptr; }
  static constexpr bool ordered(T lo, T hi) { return lo <= hi; }
  static constexpr bool within(T v, T lo, T hi) { return lo <= v && v <= hi; }
  template <typename U>
  static constexpr T cast(U v) { return (T)v; }
  // A float channel rounds (0.1 has no exact float); an integer one must keep the value and its
  // sign (on the Uno an int is 16 bits: (int)(uint16_t)-1 == -1).
  template <typename U>
  static constexpr bool fits(U v) { return IsFloat<T>::value || ((U)(T)v == v && negative(v) == negative((T)v)); }
};
template <>
struct Limits<NotNumeric> {
  static constexpr Scalar of(NotNumeric) { return Scalar(Scalar::Bits(), 0); }
  static constexpr Scalar bound(NotNumeric) { return Scalar(Scalar::Bits(), 0); }
  static constexpr InRange inRange(uint8_t) { return nullptr; }
  static constexpr bool ordered(NotNumeric, NotNumeric) { return true; }
  static constexpr bool within(NotNumeric, NotNumeric, NotNumeric) { return true; }
  template <typename U>
  static constexpr NotNumeric cast(U) { return NotNumeric(); }
  template <typename U>
  static constexpr bool fits(U) { return true; }
};
template <>
struct Limits<StructValue> : Limits<NotNumeric> {
  template <typename U>
  static constexpr StructValue cast(U) { return StructValue(); }
};

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
    // A value the type cannot hold is named first: -5 for a uint16_t would read as 65531 > max.
    return Decl(*this, unit_, description_, access_, (uint8_t)(flags_ | kHasRange), Limits<T>::cast(min),
                Limits<T>::cast(max), failsafe_, call_,
                !IsNumeric<T>::value ? kRangeOnText
                : !(Limits<T>::fits(min) && Limits<T>::fits(max)) ? kRangeValue
                : !Limits<T>::ordered(Limits<T>::cast(min), Limits<T>::cast(max)) ? kRangeOrder
                : (flags_ & kHasFailsafe) && !Limits<T>::within(failsafe_, Limits<T>::cast(min), Limits<T>::cast(max))
                    ? kFailsafeOutsideRange
                    : kNoMistake);
  }
  /// The unit the hub shows.
  ///   expose("range", rangeCm).unit("cm")
  constexpr Decl unit(const char* u) const {
    return Decl(*this, shortText(u) ? u : "", description_, access_, flags_, lo_, hi_, failsafe_, call_,
                shortText(u) ? kNoMistake : kLongText);
  }
  /// A description the hub shows.
  ///   action("beep", beep).describe("beep for ms (max 2000)")
  constexpr Decl describe(const char* d) const {
    return Decl(*this, unit_, shortText(d) ? d : "", access_, flags_, lo_, hi_, failsafe_, call_,
                shortText(d) ? kNoMistake : kLongText);
  }
  /// When the link is lost the variable (every element of an array) is set to this, or the
  /// control's function is called with it.
  ///   expose("left", left).writable().failsafe(0.0f)
  template <typename U>
  constexpr Decl failsafe(U value) const {
    static_assert(K != kMission, "failsafe(): a mission has no failsafe value (stop it in the sketch's onLinkLost())");
    static_assert(K == kVariable || K == kControl || K == kMission, "failsafe(): only a variable or a control has a failsafe value");
    return Decl(*this, unit_, description_, access_, (uint8_t)(flags_ | kHasFailsafe), lo_, hi_, Limits<T>::cast(value),
                call_,
                !IsNumeric<T>::value ? kFailsafeOnText
                : isListCode(code_) ? kListFailsafe
                : !Limits<T>::fits(value) ? kFailsafeValue
                : (flags_ & kHasRange) && !Limits<T>::within(Limits<T>::cast(value), lo_, hi_) ? kFailsafeOutsideRange
                                                                                          : kNoMistake);
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
      : memSize_(memSize), retCount_(retCount), progress_(progress), progressMax_(0), name_(shortText(name) ? name : "_"), layout_(layout),
        unit_(nullptr), description_(nullptr), data_(data),
        call_(call), thunk_(thunk), code_(code), count_(count), ret_(ret), access_(access),
        flags_(0), mistake_(validName(name) ? kNoMistake : kBadName), lo_(), hi_(), failsafe_() {}

  // The k-th piece of this channel's JSON, as channel id: four functions of four pieces each, not
  // one of sixteen (avr-g++ 5.4 paid about 20 KB for each piece it worked out from the one large
  // function, 8 from these: 32 channels with 60-character descriptions 167 MiB, then 161).
  constexpr Piece piece(uint8_t k, uint8_t id) const {
    return k < 8 ? (k < 4 ? pieces0to3(k, id) : pieces4to7(k)) : (k < 12 ? pieces8to11(k) : pieces12to15(k));
  }
  constexpr Piece pieces0to3(uint8_t k, uint8_t id) const {
    return k == 0 ? integer(id > 1 ? ",{\"id\":" : "{\"id\":", id)
         : k == 1 ? quoted(",\"n\":\"", name_)
         : k == 2 ? Piece{",\"a\":\"", kAccessLetters, access_, 0, "", "\""}
                  : typeNamed(",\"t\":\"", elementOf(code_));
  }
  constexpr Piece pieces4to7(uint8_t k) const {
    return k == 4 ? (count_ ? integer(isListCode(code_) ? ",\"vc\":" : ",\"c\":", count_) : empty())
         : k == 5 ? (layout_ ? Piece{",\"f\":[", kFields, 0, 0, layout_, "]"} : empty())
         : k == 6 ? (ret_ != kVoid ? typeNamed(",\"rt\":\"", elementOf(ret_)) : empty())
                  : (progress_ != kVoid ? typeNamed(",\"pt\":\"", progress_) : empty());
  }
  constexpr Piece pieces8to11(uint8_t k) const {
    return k == 8 ? (flags_ & kHasProgressMax ? number(",\"pmax\":", progressMax_) : empty())
         : k == 9 ? (unit_ ? quoted(",\"u\":\"", unit_) : empty())
         : k == 10 ? (flags_ & kHasRange ? number(",\"min\":", lo_) : empty())
                   : (flags_ & kHasRange ? number(",\"max\":", hi_) : empty());
  }
  constexpr Piece pieces12to15(uint8_t k) const {
    return k == 12 ? (flags_ & kHasFailsafe ? number(",\"fs\":", failsafe_) : empty())
         : k == 13 ? (description_ ? quoted(",\"d\":\"", description_) : empty())
         : k == 14 ? (retCount_ ? integer(",\"rvc\":", retCount_) : empty())
                   : literal("}");  // k == 15
  }
  // Where piece k starts in the entry (k = kPiecesPerChannel: the entry's length), each k worked
  // out once (descriptor_text.h finds a character's piece from them).
  constexpr size_t pieceStart(uint8_t id, uint8_t k) const {
    return k == 0 ? 0 : pieceStart(id, (uint8_t)(k - 1)) + pieceLength(piece((uint8_t)(k - 1), id));
  }
  constexpr size_t jsonLength(uint8_t id) const { return pieceStart(id, kPiecesPerChannel); }
  // Character i of the entry, by a walk over the pieces (what the tests read).
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
    return ChannelLimits{Limits<T>::inRange(flags_), Limits<T>::bound(lo_), Limits<T>::bound(hi_), Limits<T>::of(failsafe_)};
  }
  constexpr bool hasLimits() const { return flags_ & (kHasRange | kHasFailsafe); }
  constexpr const char* unitText() const { return unit_; }
  constexpr const char* descriptionText() const { return description_; }
  constexpr const char* layout() const { return layout_; }
  constexpr Mistake mistake() const { return mistake_; }
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
  // The session's features this channel needs (features.h).
  constexpr uint16_t features() const {
    return (uint16_t)((access_ & kStreamable ? kUsesStreams : 0) | (flags_ & kHasFailsafe ? kUsesFailsafes : 0) |
                      (flags_ & kHasFailsafe && K == kControl ? kUsesControlFailsafes : 0) |
                      (code_ == kStr ? kUsesStrings : 0) | (code_ == kStruct ? kUsesStructs : 0) |
                      (K == kControl || K == kAction ? kUsesCalls : 0) | (ret_ != kVoid && K != kMission ? kUsesReturns : 0) |
                      (isListCode(ret_) ? kUsesLists : 0) | (K == kMission ? kUsesMissions : 0) |
                      (K == kEvent ? kUsesEvents : 0) | (flags_ & kHasRange ? kUsesRanges : 0) |
                      (access_ & kWritable && K == kVariable ? kUsesWrites : 0) | (access_ & kReadable ? kUsesReads : 0) |
                      (isListCode(code_) ? kUsesLists : 0) | (large() ? kUsesLarge : 0) |
                      (K < kRemote && wireBytes() + kSampleHeader > kHelloSize ? kUsesWide : 0));
  }

 private:
  // mistake: one this option made (mistakes.h); the first one made is kept.
  constexpr Decl(const Decl& d, const char* unit, const char* description, uint8_t access, uint8_t flags, T lo, T hi,
                 T failsafe, Call call, Mistake mistake = kNoMistake)
      : memSize_(d.memSize_), retCount_(d.retCount_), progress_(d.progress_), progressMax_(d.progressMax_), name_(d.name_),
        layout_(d.layout_), unit_(unit), description_(description), data_(d.data_),
        call_(call), thunk_(d.thunk_), code_(d.code_), count_(d.count_),
        ret_(d.ret_), access_(access), flags_(flags), mistake_(d.mistake_ ? d.mistake_ : mistake), lo_(lo), hi_(hi),
        failsafe_(failsafe) {}
  constexpr Decl(const Decl& d, float progressMax)
      : memSize_(d.memSize_), retCount_(d.retCount_), progress_(d.progress_), progressMax_(progressMax), name_(d.name_),
        layout_(d.layout_),
        unit_(d.unit_), description_(d.description_), data_(d.data_), call_(d.call_), thunk_(d.thunk_), code_(d.code_),
        count_(d.count_), ret_(d.ret_), access_(d.access_), flags_((uint8_t)(d.flags_ | kHasProgressMax)),
        mistake_(d.mistake_), lo_(d.lo_), hi_(d.hi_), failsafe_(d.failsafe_) {}

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
  Mistake mistake_;
  T lo_, hi_, failsafe_;
};

}  // namespace declare
}  // namespace hubwire

#endif
