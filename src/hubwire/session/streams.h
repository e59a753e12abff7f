// The hub's stream subscriptions (docs/PROTOCOL.md 4): which channels are sampled at which
// interval, and when each sample is due. Times are the low 16 bits of millis(); only elapsed times
// are compared (now - start, unsigned), so intervals past 32.8 s work, up to the 60 s granted.
#ifndef HUBWIRE_SESSION_STREAMS_H
#define HUBWIRE_SESSION_STREAMS_H

#include <stdint.h>

#include "../config.h"

namespace hubwire {

const uint16_t kMaxStreamIntervalMs = 60000;

/// One subscription; id 0 is a free slot.
struct Subscription {
  uint8_t id, seq;
  uint16_t interval;
  uint16_t start;  // the current interval began: a sample is due interval ms after it
  uint16_t last;   // the previous sample, or the subscription

  /// Is a sample due at now?
  ///   if (s.due(now)) { ... s.sent(now); }
  bool due(uint16_t now) const { return id && (uint16_t)(now - start) >= interval; }

  /// Milliseconds since the previous sample (or the subscription), which a sample carries.
  ///   storeU16(out, s.since(now));
  uint16_t since(uint16_t now) const { return (uint16_t)(now - last); }

  /// A sample went out at now: the next seq, and the schedule kept (no drift) unless it fell
  /// more than one interval behind.
  ///   s.sent(now);
  void sent(uint16_t now) {
    ++seq;
    last = now;
    start = (uint16_t)(start + interval);
    if ((uint16_t)(now - start) >= interval) start = now;
  }
};

#if HUBWIRE_MAX_STREAMS > 0
class Streams {
 public:
  /// Ends every subscription (a new hub session, or the link lost).
  ///   streams.clear();
  void clear() {
    for (uint8_t i = 0; i < HUBWIRE_MAX_STREAMS; ++i) slots_[i].id = 0;
  }

  /// Subscribes channel id at interval ms (0 ends its subscription), due at once. interval becomes
  /// the one granted (HUBWIRE_MIN_STREAM_INTERVAL_MS..60000). False when every slot is taken.
  ///   uint16_t interval = 100; if (!streams.subscribe(id, interval, now)) nak(kErrBusy);
  bool subscribe(uint8_t id, uint16_t& interval, uint16_t now) {
    // One pass: the channel's own slot, else the first free one (samples go out in slot order).
    Subscription* slot = nullptr;
    for (uint8_t i = HUBWIRE_MAX_STREAMS; i-- > 0;) {
      Subscription& s = slots_[i];
      if (s.id == id) {
        slot = &s;
        break;
      }
      if (s.id == 0) slot = &s;
    }
    if (interval == 0) {
      if (slot) slot->id = 0;
      return true;
    }
    if (!slot) return false;
    if (slot->id != id) {
      slot->seq = 0;
      slot->last = now;  // a new subscription: its first sample reports the time since
    }
    if (interval < HUBWIRE_MIN_STREAM_INTERVAL_MS) interval = HUBWIRE_MIN_STREAM_INTERVAL_MS;
    // Elapsed times on the 16-bit clock are caught within 65,536 - interval ms of falling due:
    // a cap leaves update() seconds, not one millisecond, to see a sample is due.
    if (interval > kMaxStreamIntervalMs) interval = kMaxStreamIntervalMs;
    slot->id = id;
    slot->interval = interval;
    slot->start = (uint16_t)(now - interval);  // the next sample is due now
    return true;
  }

  /// Slot i (0..HUBWIRE_MAX_STREAMS-1), to check and send its samples.
  ///   for (uint8_t i = 0; i < HUBWIRE_MAX_STREAMS; ++i) if (streams[i].due(now)) ...
  Subscription& operator[](uint8_t i) { return slots_[i]; }

 private:
  Subscription slots_[HUBWIRE_MAX_STREAMS];
};
#endif

}  // namespace hubwire

#endif
