// The device's one transaction counter (docs/PROTOCOL.md 4.1) where more than events share it: its
// events, its mission updates and its own R, C, J to the hub. The hub keeps one duplicate memory per
// stream (the last event, the last update, the last control), so a new message of a stream must not
// carry the seq of the one the hub remembers for that stream; and an answer (seq, id) must name one
// message, so no seq is taken that a message of another stream still waits with. The counter skips
// those values: that is all it takes for no traffic mix to make a new message look like a retry.
// A sketch with events only numbers them in its event queue (++seq), which needs none of this.
#include "session.h"

#include "../channels/hub_table.h"

namespace hubwire {

uint8_t Session::takeTxn(uint8_t avoid) {
  HubLink* hub = HubwireHub<true, void>::link;
  if (hub && hub->owner != this) hub = nullptr;  // a program with several tables: another session's
  // The hub link keeps the counter when the sketch has hub channels, the missions' run time when not.
  uint8_t& counter = !HubwireMissions<true, void>::dispatch || hub ? hub->counter : missionLink.counter;
  for (;;) {
    uint8_t s = ++counter;
    if (s == avoid) continue;
    if (uses(kUsesEvents) && events_.inFlight() && s == events_.seq()) continue;
    if (HubwireMissions<true, void>::dispatch && missionLink.id && s == missionLink.seq) continue;
    if (hub && hub->inFlight && s == hub->headSeq) continue;
    return s;
  }
}

}  // namespace hubwire
