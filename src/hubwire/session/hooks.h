// The session's hooks into the parts a sketch may leave out (session.cpp, channel_io.cpp): each
// is a constant the sketch's HUBWIRE_CHANNELS sets, null without the feature, so that the
// link-time optimiser drops the call.
#ifndef HUBWIRE_SESSION_HOOKS_H
#define HUBWIRE_SESSION_HOOKS_H

#include "../channels/hub_table.h"
#include "session.h"

namespace hubwire {

// The hub link's hooks (hub_link.cpp): without hub channels hubTable() is a constant nullptr, the
// link-time optimiser drops every call, and the sketch links none of the hub link (hub_table.h).
__attribute__((always_inline)) static inline bool hubHook(Session& s, bool frame) {
  return HubwireHub<true, void>::dispatch && HubwireHub<true, void>::dispatch(s, frame);
}

// The missions' hooks (missions.cpp), folded away likewise for a sketch without missions.
__attribute__((always_inline)) static inline bool missionHook(Session& s, uint8_t what) {
  return HubwireMissions<true, void>::dispatch && HubwireMissions<true, void>::dispatch(s, what);
}

// Does one counter number more than the sketch's events (txn.cpp)? Only with missions or hub channels.
__attribute__((always_inline)) static inline bool sharedCounter() {
  return HubwireHub<true, void>::dispatch || HubwireMissions<true, void>::dispatch;
}

}  // namespace hubwire

#endif
