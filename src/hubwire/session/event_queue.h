// The device's events waiting for the hub's ACK (docs/PROTOCOL.md 4): a ring of copies, of which
// only the head is in flight. A new head gets a new seq; a retry keeps it, so the hub can tell a
// retry from a new event and deliver each exactly once.
#ifndef HUBWIRE_SESSION_EVENT_QUEUE_H
#define HUBWIRE_SESSION_EVENT_QUEUE_H

#include <stdint.h>
#include <string.h>

#include "../config.h"

namespace hubwire {

class EventQueue {
 public:
  /// One queued event: its channel id and a copy of its value.
  struct Entry {
    uint8_t id, len;
    uint8_t data[HUBWIRE_EVENT_MAX_PAYLOAD];
  };

  /// Queues a copy of the size bytes at value for event channel id; false when the queue is full.
  ///   if (!events.push(id, &value, sizeof(value))) { /* full: try again later */ }
  bool push(uint8_t id, const void* value, uint8_t size) {
    if (count_ >= HUBWIRE_EVENT_QUEUE) return false;
    Entry& e = events_[(uint8_t)(head_ + count_) % HUBWIRE_EVENT_QUEUE];  // 8-bit: the sum fits
    e.id = id;
    e.len = size;
    memcpy(e.data, value, size);
    ++count_;
    return true;
  }

  /// How many events wait (the head included).
  ///   if (events.size() == HUBWIRE_EVENT_QUEUE) { /* full */ }
  uint8_t size() const { return count_; }

  /// Is the head to be sent at now: never sent yet, or unacknowledged for HUBWIRE_EVENT_RETRY_MS?
  ///   if (events.due(now)) { const EventQueue::Entry& e = events.send(now); ... }
  bool due(uint16_t now) const {
    return count_ && (!inFlight_ || (uint16_t)(now - sentAt_) >= HUBWIRE_EVENT_RETRY_MS);
  }

  /// The head, marked sent at now; seq() is its seq (new for a new head, the same for a retry).
  ///   const EventQueue::Entry& e = events.send(now);  // then send e with events.seq()
  const Entry& send(uint16_t now) {
    if (!inFlight_) {
      ++seq_;
      inFlight_ = true;
    }
    sentAt_ = now;
    return events_[head_];
  }

  /// The seq of the head in flight (or of the last one sent).
  ///   tx.send(port, kMsgEvent, events.seq(), e.id, e.len);
  uint8_t seq() const { return seq_; }

  /// The hub answered seq for channel id (ACK, or NAK: a refused event is not retried either):
  /// the head goes when it is the event in flight. False when the answer is for no such event.
  ///   events.acked(f.seq, f.id);
  bool acked(uint8_t seq, uint8_t id) {
    if (!inFlight_ || seq != seq_ || id != events_[head_].id) return false;
    inFlight_ = false;
    head_ = (uint8_t)(head_ + 1) % HUBWIRE_EVENT_QUEUE;
    --count_;
    return true;
  }

  /// Is the head sent and waiting for its answer?
  bool inFlight() const { return inFlight_; }
  /// The next head sent takes seq s (where one counter numbers more than events: txn.cpp).
  void nextSeqIs(uint8_t s) { seq_ = (uint8_t)(s - 1); }

  /// Makes the head due at once (its seq kept: the hub may have it already), as after a new link.
  ///   events.retryNow(now);
  void retryNow(uint16_t now) { sentAt_ = (uint16_t)(now - HUBWIRE_EVENT_RETRY_MS); }

 private:
  Entry events_[HUBWIRE_EVENT_QUEUE];
  // One byte for the head (at most 63) and whether it is in flight: SRAM is the Uno's scarcest.
  uint8_t head_ : 7;
  bool inFlight_ : 1;
  uint8_t count_, seq_;
  uint16_t sentAt_;
};

}  // namespace hubwire

#endif
