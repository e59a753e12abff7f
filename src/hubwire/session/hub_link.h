// The device's side of talking to the hub's own channels (docs/PROTOCOL.md 10): its requests,
// writes and calls (R, C, J to the hub, stop-and-wait, retried with the same seq), the hub's
// events (`!`, delivered exactly once and in order), the bind report (C id 0) and the hub's health.
//
// One HubLink exists in a program, serving the session whose table declares hub channels
// (channels/hub_table.h). The session reaches it only through two hooks that test hubTable(), which
// the link-time optimiser folds: a sketch without hub channels links neither this code nor this RAM.
#ifndef HUBWIRE_SESSION_HUB_LINK_H
#define HUBWIRE_SESSION_HUB_LINK_H

#include <stdint.h>

#include "../config.h"
#include "../channels/channel.h"

namespace hubwire {

class Session;

/// Whether the hub bound what the sketch expects of it (its bind report, PROTOCOL.md 10.4).
///   kBindPending: no report yet in this hub session (again when a new hub session starts, not after
///                 a link loss with the same hub); requests wait meanwhile.
///   kBindOk:      every hub channel bound.
///   kBindFailed:  at least one did not: index is the first (1..N, the order of the remote*()
///                 declarations) and code why (2 no such name, 3 another type, 5 not writable or
///                 callable, 6 not readable). The others work; requests on that one fail with a NAK.
/// index and code mean something only in kBindFailed. A later report (the hub's channels changed)
/// replaces the status.
///   if (hub.hubBinding().state == hubwire::kBindFailed) showError(hub.hubBinding().index);
enum BindState : uint8_t { kBindPending = 0, kBindOk = 1, kBindFailed = 2 };
struct BindStatus {
  uint8_t state;  // BindState: pending until this hub session's report arrives
  uint8_t index;  // kBindFailed: the first hub id (1..N, declaration order) the hub could not bind
  uint8_t code;   // ... and why: a NAK code (UNKNOWN_CHANNEL, BAD_LENGTH, NOT_WRITABLE, NOT_READABLE)
  bool pending() const { return state == kBindPending; }
  bool ok() const { return state == kBindOk; }
};

/// The hub's heartbeats as the board heard them (PROTOCOL.md 10.6): beats heard since begin() while
/// linked (wraps, never reset), and the latest one's interval and the hub's receiver error counters
/// (the board's frames the hub dropped). Zero until the first; kept across a link loss.
///   if (hub.hubHealth().crc > 10) slowDown();
struct HubHealth {
  uint16_t beats;     // hub heartbeats heard since begin()
  uint16_t sinceMs;   // the latest one's "ms since previous": the hub's actual interval
  uint16_t crc, overflow, dropped;  // the hub's receiver error counters, as of that heartbeat
};

/// The code a fail callback gets when the hub never answered: HUBWIRE_HUB_TRIES sends
/// HUBWIRE_HUB_RETRY_MS apart, or none possible (no link, no bind report) within as long after the
/// request was queued. A write or call may or may not have been applied. Never a wire code
/// (PROTOCOL.md 5 keeps 240..255 local). Every other code is the hub's NAK, or BAD_LENGTH (3) /
/// BAD_VALUE (11) for an answer the board could not take (PROTOCOL.md 10.2).
///   void failed(uint8_t code) { if (code == hubwire::kHubTimeout) retryLater(); }
const uint8_t kHubTimeout = 0xF0;

typedef void (*HubDone)();
typedef void (*HubFail)(uint8_t code);
// Hands a typed answer to the sketch's callback (stored as HubDone, cast back here).
typedef void (*HubDeliver)(HubDone fn, const uint8_t* data, uint8_t len);

template <typename R>
void deliverAs(HubDone fn, const uint8_t* data, uint8_t) {
  R r;
  memcpy(&r, data, sizeof(R));
  reinterpret_cast<void (*)(R)>(fn)(r);
}
typedef void (*HubChunk)(uint16_t offset, uint16_t total, const uint8_t* data, uint8_t n);
void deliverChunk(HubDone fn, const uint8_t* data, uint8_t len);

class HubLink {
 public:
  // One request, write, call or descriptor read waiting for the hub; only the head is in flight.
  struct Entry {
    uint8_t id, type, len;  // hub id, message type (R, C, J), payload length
    uint8_t tries;          // sends so far (0: not sent yet)
    uint16_t at;            // when queued, then when last sent (16-bit ms)
    HubDone done;
    HubFail fail;
    HubDeliver deliver;  // typed answers (an action's return value, a chunk); nullptr: done()
    uint8_t data[HUBWIRE_HUB_MAX_VALUE];
  };

  Session* owner;              // the session whose table declares the hub channels
  const ChannelInfo* channels;  // hub id k: channels[k - 1], in flash
  uint8_t count;

  Entry queue[HUBWIRE_HUB_QUEUE];
  uint8_t head, queued;
  uint8_t counter;  // the device's transaction counter: its events, updates and R, C, J (txn.cpp)
  uint8_t headSeq;  // the seq of the head, or of the chunk request sent in its place, once sent
  bool inFlight;    // ... and it waits for its answer
  // What the hub may remember of the device's controls (PROTOCOL.md 10.2): cSeq, the last control
  // answered or left unanswered, when cValid; unsure: an earlier one may be remembered instead, so
  // the next control sends a chunk request first (clearing), whose answer ends the hub's memory.
  bool cValid, unsure, clearing;
  uint8_t cSeq;
  bool hubKnown;    // hubNonce: the hub session the link last saw (the session's, copied)
  uint32_t hubNonce;
  bool bound;       // the bind report of this hub session has arrived
  bool eventValid;  // eventSeq/eventId: the last hub event delivered (duplicates are re-acked)
  uint8_t eventSeq, eventId;
  BindStatus bind;
  HubHealth health;
};

// The program's one hub link (hub_link.cpp); zero until a session with hub channels begins.
extern HubLink hubLink;

}  // namespace hubwire

#endif
