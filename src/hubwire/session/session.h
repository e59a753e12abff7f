// The device side of a Hubwire session: handshake, heartbeats, descriptor, requests, controls,
// events and streams (docs/PROTOCOL.md 3-4), over the Port seam (port.h).
//
// The channels come from HUBWIRE_CHANNELS (../channels/declare.h): the descriptor JSON and one
// record per channel, constants in flash (HUBWIRE_FLASH, text.h: also on Teensy 4, which would copy
// plain constants to RAM). Nothing about a channel is copied into RAM, so a channel costs flash
// only: that is what lets an Uno with 2 KB of SRAM carry a dozen described channels.
#ifndef HUBWIRE_SESSION_SESSION_H
#define HUBWIRE_SESSION_SESSION_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "../config.h"
#include "../port.h"
#include "../text.h"
#include "../channels/channel.h"
#include "../wire/frame.h"
#include "../wire/messages.h"
#include "../wire/values.h"
#include "event_queue.h"
#include "fragments.h"
#include "hub_link.h"
#include "missions.h"
#include "streams.h"

namespace hubwire {

// Why begin() refused the channel table; see Session::error(). Everything else about the
// declarations is checked when the sketch compiles (declare.h).
enum SetupError : uint8_t {
  kSetupOk = 0,
  kSetupNoDeclarations,  // begin() was not called, or with an empty table
};

// Keeps a template argument from being deduced from a second parameter (emit(ev, 1.5) with
// Event<float> converts 1.5 instead of failing to deduce).
template <typename T>
struct Same {
  typedef T type;
};

// The receiver's part of the frame buffer (frameBuf_ less the writer's code byte and delimiter),
// counted in one byte where it fits (16 bits cost ~46 B more code on AVR).
#if HUBWIRE_RAW_FRAME_SIZE(HUBWIRE_MAX_PAYLOAD) <= 255
typedef uint8_t RxIndex;
#else
typedef uint16_t RxIndex;
#endif
const RxIndex kRxCapacity = HUBWIRE_RAW_FRAME_SIZE(HUBWIRE_MAX_PAYLOAD);

// Everything a Session changes while it runs, kept apart from its port so that one
// value-initialisation zeroes it all (a loop, instead of a store per member on AVR).

struct SessionState {
  // Flags, a byte each: each read-modify-write of a bit cost more flash than the bytes they take
  // (paid for by the table, no longer copied into RAM: table()).
  bool nonceDrawn_;  // nonce_ is this boot's nonce (not yet: it holds the seed)
  bool started_;  // begin() succeeded
  bool linked_;
  bool hubKnown_;  // hubNonce_ is valid
  bool beatSent_;  // a heartbeat went out since the link came up
  bool lastTxnControl_;  // duplicate suppression: lastTxn* describe a control

  // One buffer receives and sends frames: an answer is built where its question was (handlers
  // read the question first), and frames of our own wait until no frame is arriving. The writer
  // encodes in place from its first byte on, the receiver uses the rest (frame.h).
  uint8_t frameBuf_[HUBWIRE_SEND_FRAME_SIZE(HUBWIRE_MAX_PAYLOAD)];

  // The table begin() was given, read only in a program with several (table()).
  const ChannelTable* table_;

  // Session.
  uint32_t nonce_, hubNonce_;  // nonce_ holds begin()'s seed until it is drawn
  uint8_t peerMax_;  // the longest payload we send: the hub's limit, at most HUBWIRE_MAX_PAYLOAD
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

  EventQueue events_;  // the events waiting for the hub's ACK
#if HUBWIRE_MAX_STREAMS > 0
  Streams streams_;  // the hub's subscriptions
#endif
  FrameDecoderOf<RxIndex> rx_;  // zeroed with the rest; decodes into frameBuf_ (rxBuf(), kRxCapacity)
};

class Session : private SessionState {
 public:
  /// A session over a port (port.h), which it keeps a copy of; the Arduino face binds it to a
  /// Stream (Hubwire.h).
  ///   hubwire::Session session(port);
  explicit Session(const Port& port);
  // One session per port: a copy would answer the same hub twice.
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // ---- running ----

  /// Starts the session with the channels HUBWIRE_CHANNELS declared (the table is in flash,
  /// where only that macro puts it); false for an empty table. seed should differ between boots
  /// where the board can tell (a boot counter, a hardware RNG); the session nonce also mixes in
  /// the moment the hub is first heard, which differs even when the seed cannot.
  ///   session.begin(channels, bootCounter);
  bool begin(const ChannelTable& channels, uint32_t seed = 0);

  /// Reads what arrived, answers it, sends heartbeats, retries events, streams samples. Never
  /// blocks; call it from loop().
  ///   void loop() { session.update(); }
  void update();

  /// Queues an event for the hub, delivered exactly once; false when the queue is full or the
  /// event was not declared.
  ///   if (!session.emit(bumper, true)) { /* full: emit again later */ }
  template <typename T>
  bool emit(const Event<T>& ev, const typename Same<T>::type& value) {
    return emitRaw(ev.id, &value, sizeof(T));  // a scalar: its memory is its wire form
  }

  /// Called when the hub links (after the handshake).
  ///   session.onLinkUp(showConnected);
  void onLinkUp(void (*fn)()) { onLinkUp_ = fn; }
  /// The failsafe hook: the hub has gone silent (called after channels with failsafe values
  /// were reset to them and their onChange ran).
  ///   session.onLinkLost(stopMotors);
  void onLinkLost(void (*fn)()) { onLinkLost_ = fn; }

  /// Is a hub linked (handshake done, heard within its heartbeat timeout)?
  ///   digitalWrite(LED_BUILTIN, session.linked());
  bool linked() const { return linked_; }
  /// This boot's session nonce; 0 until the hub is first heard or the first announcement.
  ///   uint32_t n = session.nonce();
  uint32_t nonce() const { return nonceDrawn_ ? nonce_ : 0; }
  /// Why begin() refused the channel table, or kSetupOk.
  ///   if (session.error() != hubwire::kSetupOk) blinkForever();
  SetupError error() const { return started_ ? kSetupOk : kSetupNoDeclarations; }
  /// How many channels begin() was given.
  ///   uint8_t n = session.channelCount();
  uint8_t channelCount() const { return started_ ? table(&ChannelTable::count) : 0; }
  /// The descriptor's length in bytes, as hello announces it.
  ///   uint16_t len = session.descriptorLength();
  uint16_t descriptorLength() const { return started_ ? table(&ChannelTable::jsonLength) : 0; }
  /// The descriptor's FNV-1a hash, as hello announces it.
  ///   uint32_t h = session.descriptorHash();
  uint32_t descriptorHash() const { return started_ ? table(&ChannelTable::hash) : 0; }
  /// Events waiting for the hub's ACK.
  ///   if (session.eventsQueued() == HUBWIRE_EVENT_QUEUE) { /* full */ }
  uint8_t eventsQueued() const { return events_.size(); }
  /// The receiver's error counters (bad CRC, overflow, dropped), as heartbeats report them.
  ///   uint16_t bad = session.counters().crc;
  const LinkCounters& counters() const { return rx_.counters; }

  // ---- the hub's own channels, declared with remote(), remoteAction(), remoteEvent() (hub_link.h,
  // PROTOCOL.md 10). None of these waits: each queues and returns true, or false when it cannot (not
  // begun, the variable or action not declared for that use, or HUBWIRE_HUB_QUEUE requests waiting
  // already). A queued request is sent once the hub's bind report has arrived, one at a time, and
  // ends in exactly one of its callbacks: done, or fail(code) with the hub's NAK code (2, 3, 4, 5, 6,
  // 9, 11, 12), BAD_LENGTH / BAD_VALUE for an answer the board could not take, or kHubTimeout. ----

  /// Asks the hub for a value declared with remote(); its answer lands in var, then done runs.
  ///   hub.request(setpoint, setpointArrived, setpointFailed);
  template <typename T>
  bool request(T& var, HubDone done = nullptr, HubFail fail = nullptr) {
    return hubQueue(kMsgRequest, &var, done, fail);
  }
  /// Writes var's value (as it is now) to a hub value declared with remote(...).writable() or
  /// writeOnly(); done runs on the hub's ACK, fail with its NAK code. Applied exactly once.
  ///   hub.write(report, nullptr, reportRefused);
  template <typename T>
  bool write(const T& var, HubDone done = nullptr, HubFail fail = nullptr) {
    static_assert(sizeof(T) <= HUBWIRE_HUB_MAX_VALUE, "value larger than HUBWIRE_HUB_MAX_VALUE: raise it");
    return hubQueue(kMsgControl, &var, done, fail);
  }
  /// Calls a hub action declared with remoteAction(); done gets its return value.
  ///   hub.call(dock, 0.5f, docked, dockFailed);   // RemoteAction<bool(float)>; void docked(bool)
  template <typename R, typename A>
  bool call(RemoteAction<R(A)>& action, const typename Same<A>::type& arg,
            void (*done)(typename Same<R>::type) = nullptr, HubFail fail = nullptr) {
    static_assert(sizeof(A) <= HUBWIRE_HUB_MAX_VALUE, "argument larger than HUBWIRE_HUB_MAX_VALUE: raise it");
    return hubCall(&action, &arg, sizeof(A), reinterpret_cast<HubDone>(done), fail, &deliverAs<R>);
  }
  template <typename A>
  bool call(RemoteAction<void(A)>& action, const typename Same<A>::type& arg, HubDone done = nullptr,
            HubFail fail = nullptr) {
    static_assert(sizeof(A) <= HUBWIRE_HUB_MAX_VALUE, "argument larger than HUBWIRE_HUB_MAX_VALUE: raise it");
    return hubCall(&action, &arg, sizeof(A), done, fail, nullptr);
  }
  template <typename R>
  bool call(RemoteAction<R()>& action, void (*done)(typename Same<R>::type) = nullptr, HubFail fail = nullptr) {
    return hubCall(&action, nullptr, 0, reinterpret_cast<HubDone>(done), fail, &deliverAs<R>);
  }
  bool call(RemoteAction<void()>& action, HubDone done = nullptr, HubFail fail = nullptr) {
    return hubCall(&action, nullptr, 0, done, fail, nullptr);
  }
  /// Reads the hub's own descriptor (JSON) from offset, one chunk: chunk(offset, total, data, n).
  ///   hub.readHubDescriptor(0, gotChunk);
  bool readHubDescriptor(uint16_t offset, HubChunk chunk, HubFail fail = nullptr);
  /// Has the hub bound the declarations (pending, ok, or the first hub id it could not bind)?
  ///   if (hub.hubBinding().state == hubwire::kBindFailed) showError(hub.hubBinding().index);
  BindStatus hubBinding() const { return hubLink.bind; }
  /// The hub's heartbeat interval as measured by the hub and its receiver's error counters.
  ///   if (hub.hubHealth().crc > 10) slowDown();
  const HubHealth& hubHealth() const { return hubLink.health; }
  /// Requests, writes and calls not yet answered.
  ///   if (hub.hubQueued() == HUBWIRE_HUB_QUEUE) { /* full */ }
  uint8_t hubQueued() const { return hubLink.queued; }

  // ---- missions, declared with mission() (missions.h): the sketch reports from loop(); each call
  // returns at once, false when the mission has no run going. ----

  /// The run's progress; a newer value replaces one not yet sent (the latest wins).
  ///   hub.progress(drive, metres);
  template <typename S, typename P>
  bool progress(Mission<S, P>& m, const typename Same<P>::type& value) {
    return missionReport(m, kMissionProgress, &value, sizeof(P), m.progress_);
  }
  template <typename S>
  bool progress(Mission<S, void>& m) { return missionReport(m, kMissionProgress, nullptr, 0, m.progress_); }
  /// Ends the run as succeeded, with its result (none for a void result); sent after the progress
  /// already sent, in place of a progress not yet sent.
  ///   hub.finish(drive, metres);
  template <typename S, typename P>
  bool finish(Mission<S, P>& m, const typename Same<typename Mission<S, P>::Result>::type& result) {
    return missionReport(m, kMissionSucceeded, &result, sizeof(result), m.result_);
  }
  template <typename G, typename P>
  bool finish(Mission<void(G), P>& m) { return missionReport(m, kMissionSucceeded, nullptr, 0, m.result_); }
  template <typename P>
  bool finish(Mission<void(), P>& m) { return missionReport(m, kMissionSucceeded, nullptr, 0, m.result_); }
  /// Ends the run as failed with the sketch's own code (1..255).
  ///   hub.fail(drive, kBlocked);
  template <typename S, typename P>
  bool fail(Mission<S, P>& m, uint8_t code) {
    return code != 0 && missionReport(m, kMissionFailed, &code, 1, m.result_);
  }

 private:
  // Missions (missions.cpp), reached only when the sketch declares one.
  friend bool missionDispatch(Session& s, uint8_t what);
  bool missionFrame(const Frame& f);
  bool missionAck(const Frame& f);
  void missionPoll(uint16_t now);
  uint8_t missionStart(const Frame& f, const ChannelInfo& ch, MissionState& m);
  uint8_t missionTake();
  void missionSend();

  // The hub's own channels (hub_link.cpp), reached only through the sketch's hub table.
  friend bool hubDispatch(Session& s, bool frame);
  bool hubMine();
  void hubSessionCheck();
  bool hubQueue(uint8_t type, const void* var, HubDone done, HubFail fail);
  bool hubCall(const void* handle, const void* arg, uint8_t len, HubDone done, HubFail fail, HubDeliver deliver);
  HubLink::Entry* hubPush(uint8_t id, uint8_t type, HubDone done, HubFail fail);
  bool hubFind(uint8_t id, ChannelInfo& ch);
  bool hubFrame(const Frame& f);
  void hubAnswer(const Frame& f);
  void hubEvent(const Frame& f);
  void hubBind(const Frame& f);
  void hubPoll(uint16_t now);
  void hubAnswered(uint8_t type);
  bool hubCleared(const Frame& f);

  // The device's one transaction counter (txn.cpp), where hub channels or missions share it.
  uint8_t takeTxn(uint8_t avoid);

  // Values too long for one frame (fragments.cpp), reached only where the sketch declares one.
  friend void fragmentReceived(Session& s, const Frame& f);
  friend bool sendLarge(Session& s, uint8_t type, uint8_t seq, uint8_t id, const ChannelInfo& ch,
                        const uint8_t* prefix, uint8_t prefixLen, bool room);

  // A field of the table begin() took. In a program with one table, the sketch's constant
  // (channel.h), which the compiler folds into the code; else read from flash where table_ points.
  template <typename T>
  HUBWIRE_ALWAYS_INLINE T table(T ChannelTable::*field) const {
    return sketchTable.count ? sketchTable.*field : flashRead(&(table_->*field));
  }
  bool find(uint8_t id, ChannelInfo& ch);  // ch describes channel id afterwards
  void applyFailsafes();
  bool emitRaw(uint8_t id, const void* value, uint8_t size);

  void handle(const Frame& f);
  void onHello(const Frame& f);
  void onChunk(const Frame& f);
  void onRequest(const Frame& f);
  void onControl(const Frame& f);
  void onSubscribe(const Frame& f);
  void onAck(const Frame& f, bool nak);
  void newHubSession(uint32_t nonce);
  void loseLink(uint16_t now);
  void sendHello(uint8_t flags);  // kHelloDevice, and kHelloReply for an answer
  HUBWIRE_NOINLINE void drawNonce(const uint8_t* hubNonce);  // two callers: one copy
  void sendHeartbeat(uint16_t now);
  void sendEvent(uint16_t now);
  uint16_t ms() { return (uint16_t)portMillis(port_); }
  void sendSamples(uint16_t now);
  void sendNak(uint8_t code);  // answers the frame received with a NAK (reply())
  // Every frame of the device goes out here: one call with four byte arguments at each sender
  // instead of the port and buffer loaded at each (out of line: Uno flash -98 B in Minimal).
  HUBWIRE_NOINLINE void send(uint8_t type, uint8_t seq, uint8_t id, uint8_t len) {
    tx().send(port_, type, seq, id, len);
  }
  void reply(uint8_t type, uint8_t len);  // answers the frame received: its seq and id
  uint8_t maxOut() const { return peerMax_; }

  // The receiver's part of frameBuf_: the writer's code byte and delimiter lie around it.
  uint8_t* rxBuf() { return frameBuf_ + 1; }
  Frame received() const { return rx_.frame(frameBuf_ + 1); }  // the frame feed() completed

  Port port_;
  // The writer over frameBuf_: made where it is used, so the session stores no pointer for it.
  BasicFrameWriter<HUBWIRE_MAX_PAYLOAD> tx() { return BasicFrameWriter<HUBWIRE_MAX_PAYLOAD>(frameBuf_); }
};

}  // namespace hubwire

#endif
