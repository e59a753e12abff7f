// Values whose message does not fit one frame travel as fragments (`F`, docs/PROTOCOL.md 12).
//
// Receiving: one reassembly at a time, into ONE buffer that HUBWIRE_CHANNELS sizes to the largest
// writable value or argument that does not fit a frame. Sending: a large `r` answer or `D` sample
// goes out fragment after fragment straight from the sketch's variable, within one update(), so
// the value is never torn and no copy of it is needed.
//
// Paying only for what is used: the session reaches this file through a few hooks that call
// HubwireLarge<true, void>::receive and ::send, which the library defines weakly as nullptr
// (large_flag.cpp) and HUBWIRE_CHANNELS defines again, with the reassembly buffer (::state), only
// for a sketch with a large value (the `large` feature, features.h): the pattern of the hub
// channels' table (channels/hub_table.h). A direct call under a test of the feature would not do:
// the optimiser clones a function for its call sites before it folds the test away.
#ifndef HUBWIRE_SESSION_FRAGMENTS_H
#define HUBWIRE_SESSION_FRAGMENTS_H

#include <stdint.h>

#include "../channels/channel.h"
#include "../wire/frame.h"

namespace hubwire {

// The reassembly in progress (total 0: none); the buffer's bytes follow it (LargeBuffer).
struct Reassembly {
  uint8_t type, seq, id;
  uint16_t total, next;
};
template <uint16_t N>
struct LargeBuffer : Reassembly {
  uint8_t data[N];
};
inline uint8_t* reassemblyData(Reassembly* r) { return reinterpret_cast<uint8_t*>(r) + sizeof(Reassembly); }

class Session;
// A fragment arrived (session.cpp's hook).
void fragmentReceived(Session& s, const Frame& f);
typedef void (*FragmentReceiver)(Session& s, const Frame& f);
// Sends type (seq, id) carrying prefix (prefixLen bytes) then ch's value: one frame if it fits the
// hub, else fragments. With room, only if the port has room for the first frame now (samples);
// false when it did not send. Type kMsgRequest: answers a window request (PROTOCOL.md 12.8) whose
// 4-byte payload is prefix, with one `r` frame (or NAK BAD_OFFSET).
bool sendLarge(Session& s, uint8_t type, uint8_t seq, uint8_t id, const ChannelInfo& ch, const uint8_t* prefix,
               uint8_t prefixLen, bool room);
typedef bool (*LargeSender)(Session& s, uint8_t type, uint8_t seq, uint8_t id, const ChannelInfo& ch,
                            const uint8_t* prefix, uint8_t prefixLen, bool room);

namespace declare {
// The sketch's reassembly buffer: none without large writes.
template <uint16_t N>
struct LargeStore {
  static LargeBuffer<N> buffer;
  static constexpr Reassembly* get() { return &buffer; }
};
template <uint16_t N>
LargeBuffer<N> LargeStore<N>::buffer;
template <>
struct LargeStore<0> {
  static constexpr Reassembly* get() { return nullptr; }
};
}  // namespace declare

}  // namespace hubwire

// As HubwireHub (hub_table.h): <true, void> is the one the session reads.
template <bool Declared, typename Tag>
struct HubwireLarge {
  static ::hubwire::Reassembly* const state;  // nullptr: no large writes (capacity 0)
  static const uint16_t capacity;
  static const ::hubwire::FragmentReceiver receive;
  static const ::hubwire::LargeSender send;
};
template <>
::hubwire::Reassembly* const HubwireLarge<true, void>::state;
template <>
const uint16_t HubwireLarge<true, void>::capacity;
template <>
const ::hubwire::FragmentReceiver HubwireLarge<true, void>::receive;
template <>
const ::hubwire::LargeSender HubwireLarge<true, void>::send;

namespace hubwire {
// The payload length of a frame the session handles: a reassembled message's payload is the
// reassembly buffer, whose length is where the reassembly ended (fragments.cpp).
HUBWIRE_ALWAYS_INLINE uint16_t wholeLength(const Frame& f) {
  Reassembly* r = HubwireLarge<true, void>::state;
  return r && f.payload == reassemblyData(r) ? r->next : f.len;
}
}  // namespace hubwire

#endif
