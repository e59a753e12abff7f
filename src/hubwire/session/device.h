// The device side of a Hubwire session: handshake, heartbeats, descriptor, requests, controls,
// events and streams (docs/PROTOCOL.md 3-4), over the Port seam (port.h).
//
// Channels are declared in a function of the sketch ("declarations"), which the device runs again
// whenever it needs a channel's facts (to describe it, to find channel 3, to apply failsafes).
// Nothing about a channel is copied into RAM, so a channel costs flash only: that is what lets an
// Uno with 2 KB of SRAM carry a dozen described channels. Keep the function to declarations.
#ifndef HUBWIRE_SESSION_DEVICE_H
#define HUBWIRE_SESSION_DEVICE_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "../config.h"
#include "../port.h"
#include "../text.h"
#include "../wire/frame.h"
#include "../wire/types.h"
#include "json_window.h"
#include "protocol.h"

namespace hubwire {

enum Access : uint8_t { kReadable = 1, kWritable = 2, kCallable = 4, kEventAccess = 8, kStreamable = 16 };

// Why begin() refused the declarations; see Device::error() and errorChannel().
// Types and sizes are checked when the sketch compiles (static_assert), and names by the hub, which
// reports a malformed or repeated name with its channel when it reads the descriptor: the board
// spends no flash on either. What only the running board can tell is checked by begin().
enum SetupError : uint8_t {
  kSetupOk = 0,
  kSetupNoDeclarations,
  kSetupTooManyChannels,  // more than HUBWIRE_MAX_CHANNELS
  kSetupBadLayout,        // struct layout text malformed, or its size differs from sizeof(struct)
};

// Keeps a template argument from being deduced from a second parameter (emit(ev, 1.5) with
// Event<float> converts 1.5 instead of failing to deduce).
template <typename T>
struct Same {
  typedef T type;
};

// A declared event: keep one per event (a global), emit with Device::emit().
template <typename T>
struct Event {
  uint8_t id = 0;  // set by begin()
};

// Calls a sketch function with a typed argument and return value, both as little-endian bytes.
// Returns false when the function refused the value (controls returning bool).
typedef bool (*Thunk)(void (*fn)(), const uint8_t* arg, uint8_t* ret);

// Room for one scalar of any type the board carries: a range limit or a failsafe value, kept as
// the bytes of the channel's own type so that no value is ever converted (no soft-float code on
// AVR). An integer, so that it travels in registers.
#if HUBWIRE_HAS_F64
typedef uint64_t ScalarBits;
#else
typedef uint32_t ScalarBits;
#endif
template <size_t N>
struct UintOf;
template <>
struct UintOf<1> {
  typedef uint8_t type;
};
template <>
struct UintOf<2> {
  typedef uint16_t type;
};
template <>
struct UintOf<4> {
  typedef uint32_t type;
};
template <>
struct UintOf<8> {
  typedef uint64_t type;
};
template <typename T>
ScalarBits bitsOf(T v) {
  // Through an unsigned integer of T's own size, which stays in registers (copying into the wider
  // ScalarBits directly goes through the stack on AVR, in every declaration with a range).
  typename UintOf<sizeof(T)>::type u;
  memcpy(&u, &v, sizeof(T));
  return u;  // little-endian (config.h): the value sits in the low bytes
}
// Writes an integer or float as a JSON number.
template <typename T>
void putNumber(JsonWindow& j, T v) {
  const TypeCode c = TypeOf<T>::code;
  if (c == kI8 || c == kI16 || c == kI32) {
    j.integer((int32_t)v);
  } else {
    j.uinteger((uint32_t)v);
  }
}
inline void putNumber(JsonWindow& j, float v) { j.number(v); }
inline void putNumber(JsonWindow& j, double v) { j.number((float)v); }

// What a range or failsafe needs to know about its type, instantiated only for the types that are
// given one: a sketch without float ranges links no float comparison or printing.
// print != null: writes *v as a JSON number and returns true. Otherwise: *v within [*lo, *hi]?
typedef bool (*ScalarOps)(const void* v, const ScalarBits* lo, const ScalarBits* hi, JsonWindow* print);

template <typename T>
bool scalarOps(const void* v, const ScalarBits* lo, const ScalarBits* hi, JsonWindow* print) {
  T x, a, b;
  memcpy(&x, v, sizeof(T));
  if (print) return putNumber(*print, x), true;
  memcpy(&a, lo, sizeof(T));
  memcpy(&b, hi, sizeof(T));
  return x >= a && x <= b;  // NaN fails
}

// Everything the declarations say about the channel being visited.
struct ChannelInfo {
  Text name, unit, description;
  ValueType type;    // value, call argument, or event value
  TypeCode ret;      // callables: return value (a scalar)
  void* data;        // the variable behind a readable/writable channel
  void (*fn)();      // change callback, or the function a control/action calls
  Thunk thunk;       // how to call fn with an argument
  ScalarOps ops;     // range / failsafe: their type's comparison and printing
  ScalarBits min, max, failsafe;
  uint16_t memSize;  // sizeof the variable, to check struct layouts
  uint8_t access;
  uint8_t flags;
  uint8_t* eventId;  // events: the handle's id, set by begin()
  void (*fields)(JsonWindow& j, const ValueType& t);  // structs: describes the fields
};

// Everything a Device changes while it runs, kept apart from its references so that one
// value-initialisation zeroes it all (a loop, instead of a store per member on AVR).
struct DeviceState {
  enum Mode : uint8_t { kIdle, kCheck, kFind, kDescribe, kFailsafe };

  // Flags, one bit each (SRAM is the Uno's scarcest resource).
  bool skip_ : 1;           // visit: this declaration is not the one being built
  bool pending_ : 1;        // visit: a visited channel awaits finishChannel()
  bool nonceDrawn_ : 1;     // nonce_ is this boot's nonce (not yet: it holds the seed)
  bool started_ : 1;        // begin() succeeded
  bool linked_ : 1;
  bool hubKnown_ : 1;       // hubNonce_ is valid
  bool beatSent_ : 1;       // a heartbeat went out since the link came up
  bool lastTxnValid_ : 1;   // duplicate suppression: lastTxn* describe a transaction
  bool lastTxnControl_ : 1;  // ... which was a control
  bool eventInFlight_ : 1;  // the head event was sent and awaits its ACK

  // One buffer receives and sends frames: an answer is built where its question was (handlers
  // read the question first), and frames of our own wait until no frame is arriving.
  uint8_t frameBuf_[HUBWIRE_RAW_FRAME_SIZE(HUBWIRE_MAX_PAYLOAD)];

  // Declarations and the visit in progress.
  void (*declarations_)();
  Mode mode_;
  uint8_t visitId_;   // id of the channel being visited (1-based, 0 before the first)
  uint8_t target_;    // kFind: wanted id
  JsonWindow* json_;  // kDescribe
  uint8_t channelCount_;
  SetupError error_;
  uint8_t errorChannel_;
  uint16_t descLength_;
  uint32_t descHash_;
  // Where a channel's JSON starts, from the last chunk served: the next chunk resumes there
  // instead of producing the descriptor from its first character again.
  uint8_t resumeId_, resumeFrom_;
  uint16_t resumePos_;

  // Session.
  uint32_t nonce_, hubNonce_;  // nonce_ holds begin()'s seed until it is drawn
  uint8_t peerMax_;
  // Times are the low 16 bits of millis(): every interval here stays below 65 s, so differences
  // are exact as long as update() runs at least that often.
  uint16_t lostAfterMs_;  // the hub's heartbeat interval x HUBWIRE_LOST_AFTER_BEATS
  uint16_t lastRx_;
  uint16_t lastSent_;  // the last heartbeat while linked, the last announcement while not
  uint16_t lastByte_;  // when a byte last arrived
  uint16_t beatCounter_;
  void (*onLinkUp_)();
  void (*onLinkLost_)();

  // Duplicate suppression: the last hub transaction and, for a control, the answer it got.
  uint8_t lastTxnSeq_, lastTxnId_;
  uint8_t replyType_, replyLen_;
  uint8_t replyData_[HUBWIRE_MAX_RETURN];

  // Events: a ring; only the head is in flight.
  struct QueuedEvent {
    uint8_t id, len;
    uint8_t data[HUBWIRE_EVENT_MAX_PAYLOAD];
  };
  QueuedEvent events_[HUBWIRE_EVENT_QUEUE];
  uint8_t eventHead_, eventCount_, eventSeq_;
  uint16_t eventSentAt_;

  // Subscriptions (id 0 = free slot).
  // Times are the low 16 bits of millis(). Only elapsed times are compared (now - start, unsigned),
  // so intervals past 32.8 s work (up to the 60 s granted); a due time compared as signed would not.
  struct Subscription {
    uint8_t id, seq;
    uint16_t interval;
    uint16_t start;  // the current interval began: a sample is due interval ms after it
    uint16_t last;   // the previous sample, or the subscription
  };
#if HUBWIRE_MAX_STREAMS > 0
  Subscription streams_[HUBWIRE_MAX_STREAMS];
#endif
};

class Device : private DeviceState {
 public:
  enum Flags : uint8_t { kHasRange = 1, kHasFailsafe = 2 };

  // Returned by every declaration; chain options onto it. T is the channel's scalar type (range
  // and failsafe take values of it), or NotNumeric for strings, structs and events. Kind says what
  // was declared: an option that makes no sense for it (an event made writable, a control given
  // onChange) fails to compile with the reason, instead of misbehaving on the board.
  struct NotNumeric {};
  enum Kind : uint8_t { kVariable, kControl, kAction, kEvent };
  template <typename T, Kind K = kVariable>
  class Builder {
   public:
    Builder& writable() {
      static_assert(K == kVariable, "writable(): only a variable declared with expose() can be written by the hub");
      return dev_.addAccess(kWritable), *this;
    }
    Builder& streamable() {
      static_assert(K == kVariable, "streamable(): only a variable declared with expose() can be streamed");
      return dev_.addAccess(kStreamable), *this;
    }
    // Writes (a control's or action's argument) outside [min, max], any element of an array, are
    // refused with NAK OUT_OF_RANGE.
    Builder& range(T min, T max) {
      static_assert(K != kEvent, "range(): an event has no range (the sketch sets its value)");
      return dev_.setRange(bitsOf(min), bitsOf(max), &scalarOps<T>), *this;
    }
    Builder& unit(Text u) { return dev_.setText(0, u), *this; }
    Builder& describe(Text d) { return dev_.setText(1, d), *this; }
    // When the link is lost the variable (every element of an array) is set to this, or the
    // control's function is called with it.
    Builder& failsafe(T value) {
      static_assert(K == kVariable || K == kControl, "failsafe(): only a variable or a control has a failsafe value");
      return dev_.setFailsafe(bitsOf(value), &scalarOps<T>), *this;
    }
    // Called after the hub wrote a new value into the variable.
    Builder& onChange(void (*fn)()) {
      static_assert(K == kVariable, "onChange(): only a variable declared with expose() has one (a control calls its function)");
      return dev_.setChange(fn), *this;
    }

   private:
    friend class Device;
    Builder(Device& d) : dev_(d) {}  // NOLINT: declarations return *this
    Device& dev_;
  };

  explicit Device(Port& port);

  // ---- declarations: call these only inside the function given to begin() ----
  // A declaration the library cannot carry fails to compile, saying why.

  // A variable (scalar, fixed array, char[] string): readable; options make it writable etc.
  template <typename T>
  Builder<T> expose(Text name, T& var) {
    checkValue<T, sizeof(T)>();
    return declare(name, &var, TypeOf<T>::code, 0, sizeof(T), kReadable);
  }
  template <typename T, size_t N>
  Builder<T> expose(Text name, T (&arr)[N]) {
    static_assert(N <= 255, "arrays hold at most 255 elements");
    checkValue<T, sizeof(arr)>();
    return declare(name, arr, TypeOf<T>::code, (uint8_t)N, sizeof(arr), kReadable);
  }
  template <size_t N>
  Builder<NotNumeric> expose(Text name, char (&str)[N]) {
    static_assert(N >= 2 && N <= 256, "a string channel needs a char[2..256] (one byte for the NUL)");
    static_assert(N + kSampleHeader <= HUBWIRE_MAX_PAYLOAD, "string longer than HUBWIRE_MAX_PAYLOAD - 3: raise it");
    return declare(name, str, kStr, (uint8_t)(N - 1), N, kReadable);
  }
  // A struct with named fields, laid out by text such as F("ax:f32,ay:f32,gyro:i16[3]").
  template <typename T>
  Builder<NotNumeric> expose(Text name, T& var, Text layout) {
    static_assert(sizeof(T) + kSampleHeader <= HUBWIRE_MAX_PAYLOAD, "struct larger than HUBWIRE_MAX_PAYLOAD - 2: raise it");
    return declareStruct(name, &var, layout, sizeof(T));
  }

  // A write-only control: the hub's value is handed to fn. A bool-returning fn may refuse it.
  template <typename T>
  Builder<T, kControl> control(Text name, void (*fn)(T)) {
    checkValue<T, sizeof(T)>();
    return declareCall(name, kWritable, TypeOf<T>::code, kVoid, (void (*)())fn, &callVoid<T>);
  }
  template <typename T>
  Builder<T, kControl> control(Text name, bool (*fn)(T)) {
    checkValue<T, sizeof(T)>();
    return declareCall(name, kWritable, TypeOf<T>::code, kVoid, (void (*)())fn, &callChecked<T>);
  }

  // A callable action: the hub calls fn with an argument and gets its return value.
  template <typename R, typename A>
  Builder<A, kAction> action(Text name, R (*fn)(A)) {
    checkValue<A, sizeof(A)>();
    checkReturn<R>();
    return declareCall(name, kCallable, TypeOf<A>::code, TypeOf<R>::code, (void (*)())fn, &callRet<R, A>);
  }
  template <typename A>
  Builder<A, kAction> action(Text name, void (*fn)(A)) {
    checkValue<A, sizeof(A)>();
    return declareCall(name, kCallable, TypeOf<A>::code, kVoid, (void (*)())fn, &callVoid<A>);
  }
  template <typename R>
  Builder<NotNumeric, kAction> action(Text name, R (*fn)()) {
    checkReturn<R>();
    return declareCall(name, kCallable, kVoid, TypeOf<R>::code, (void (*)())fn, &callNoArg<R>);
  }
  Builder<NotNumeric, kAction> action(Text name, void (*fn)()) {
    return declareCall(name, kCallable, kVoid, kVoid, fn, &callPlain);
  }

  // An event the sketch emits; the hub is told exactly once.
  template <typename T>
  Builder<NotNumeric, kEvent> event(Text name, Event<T>& ev) {
    checkValue<T, sizeof(T)>();
    static_assert(sizeof(T) <= HUBWIRE_EVENT_MAX_PAYLOAD, "event value larger than HUBWIRE_EVENT_MAX_PAYLOAD: raise it");
    declare(name, nullptr, TypeOf<T>::code, 0, sizeof(T), kEventAccess);
    if (!skip_) info_->eventId = &ev.id;
    return *this;
  }

  // ---- running ----

  // Checks the declarations and computes the descriptor hash. false when a declaration is wrong:
  // error() and errorChannel() say which and why. seed should differ between boots where the
  // board can tell (a boot counter, a hardware RNG); the session nonce also mixes in the moment
  // the hub is first heard, which differs even when the seed cannot.
  bool begin(Text name, void (*declarations)(), Text firmware = Text(), uint32_t seed = 0);
  // Reads what arrived, answers it, sends heartbeats, retries events, streams samples. Never blocks.
  void update();

  // Queues an event for the hub; false when the queue is full or the event was not declared.
  template <typename T>
  bool emit(const Event<T>& ev, const typename Same<T>::type& value) {
    return emitRaw(ev.id, &value, sizeof(T));  // a scalar: its memory is its wire form
  }

  void onLinkUp(void (*fn)()) { onLinkUp_ = fn; }
  // The failsafe hook: the hub has gone silent (after channels with failsafe values were reset).
  void onLinkLost(void (*fn)()) { onLinkLost_ = fn; }

  bool linked() const { return linked_; }
  // This boot's session nonce; 0 until the hub is first heard or the first announcement.
  uint32_t nonce() const { return nonceDrawn_ ? nonce_ : 0; }
  SetupError error() const { return error_; }
  uint8_t errorChannel() const { return errorChannel_; }
  uint8_t channelCount() const { return channelCount_; }
  uint16_t descriptorLength() const { return descLength_; }
  uint32_t descriptorHash() const { return descHash_; }
  uint8_t eventsQueued() const { return eventCount_; }
  const LinkCounters& counters() const { return rx_.counters; }

 private:
  Device& declare(Text name, void* data, TypeCode code, uint8_t count, uint16_t memSize, uint8_t access);
  Device& declareStruct(Text name, void* data, Text layout, uint16_t memSize);
  Device& declareCall(Text name, uint8_t access, TypeCode arg, TypeCode ret, void (*fn)(), Thunk thunk);
  // Not inlined: each is called from every declaration of every sketch, where a call is smaller.
  void addAccess(uint8_t a);
  void setRange(ScalarBits min, ScalarBits max, ScalarOps ops) HUBWIRE_NOINLINE;
  void setFailsafe(ScalarBits value, ScalarOps ops) HUBWIRE_NOINLINE;
  void setText(uint8_t which, Text t) HUBWIRE_NOINLINE;  // 0 unit, 1 description
  void setChange(void (*fn)()) HUBWIRE_NOINLINE;
  void finishChannel();  // the visited channel is complete: act on it for the current mode
  // Runs the declarations with scratch as the channel being visited (scratch lives on the caller's
  // stack: a channel's facts take RAM only while they are being used).
  void visit(Mode mode, ChannelInfo& scratch, uint8_t target = 0);
  bool find(uint8_t id, ChannelInfo& ch);  // ch describes channel id afterwards
  void describeChannel();
  static void describeFields(JsonWindow& j, const ValueType& t);
  uint16_t describe(uint16_t start, uint16_t len, uint8_t* out);  // copies a window of the JSON
  void describeAll(JsonWindow& j);
  void describeHead(JsonWindow& j);  // {"p":1,"n":...,"ch":[
  void checkChannel();
  bool emitRaw(uint8_t id, const void* value, uint8_t size);

  void handle(const Frame& f);
  void onHello(const Frame& f);
  void onChunk(const Frame& f);
  void onRequest(const Frame& f);
  void onControl(const Frame& f);
  void onSubscribe(const Frame& f);
  void onAck(const Frame& f, bool nak);
  void newHubSession(uint32_t nonce);
  void loseLink();
  void sendHello(bool reply);
  void drawNonce(uint32_t hubNonce);
  static uint32_t mixNonce(uint32_t h, uint32_t v) HUBWIRE_NOINLINE;
  void sendHeartbeat(uint16_t now);
  void sendEvent(uint16_t now);
  uint16_t ms() { return (uint16_t)portMillis(port_); }
  void sendSamples(uint16_t now);
  void sendNak(const Frame& f, uint8_t code);
  void reply(uint8_t type, const Frame& f, uint8_t len);
  uint8_t maxOut() const { return peerMax_ < HUBWIRE_MAX_PAYLOAD ? peerMax_ : HUBWIRE_MAX_PAYLOAD; }

  template <typename T, size_t Bytes>
  static void checkValue() {
    static_assert(TypeOf<T>::code != kVoid, "Hubwire carries bool, 8/16/32-bit integers, float and double");
    static_assert(Bytes + kSampleHeader <= HUBWIRE_MAX_PAYLOAD, "value larger than HUBWIRE_MAX_PAYLOAD - 2: raise it");
  }
  template <typename R>
  static void checkReturn() {
    static_assert(TypeOf<R>::code != kVoid, "Hubwire carries bool, 8/16/32-bit integers, float and double");
    static_assert(sizeof(R) <= HUBWIRE_MAX_RETURN, "return value larger than HUBWIRE_MAX_RETURN: raise it");
  }

  template <typename T>
  static bool callVoid(void (*fn)(), const uint8_t* arg, uint8_t*) {
    T a;
    memcpy(&a, arg, sizeof(T));
    ((void (*)(T))fn)(a);
    return true;
  }
  template <typename T>
  static bool callChecked(void (*fn)(), const uint8_t* arg, uint8_t*) {
    T a;
    memcpy(&a, arg, sizeof(T));
    return ((bool (*)(T))fn)(a);
  }
  template <typename R, typename A>
  static bool callRet(void (*fn)(), const uint8_t* arg, uint8_t* ret) {
    A a;
    memcpy(&a, arg, sizeof(A));
    R r = ((R(*)(A))fn)(a);
    memcpy(ret, &r, sizeof(R));
    return true;
  }
  template <typename R>
  static bool callNoArg(void (*fn)(), const uint8_t*, uint8_t* ret) {
    R r = ((R(*)())fn)();
    memcpy(ret, &r, sizeof(R));
    return true;
  }
  static bool callPlain(void (*fn)(), const uint8_t*, uint8_t*) {
    fn();
    return true;
  }

  Port& port_;
  FrameReceiver rx_;
  FrameWriter tx_;
  Text name_, firmware_;
  ChannelInfo* info_;  // the channel being visited, during a visit
};

}  // namespace hubwire

#endif
