// A sketch with a mission and an event, no hub channels, for test_mission_seq.cpp (a file may hold
// one table with missions).
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

using namespace hubwire;

Mission<uint8_t(uint8_t), uint16_t> lift;  // id 1
Event<uint16_t> tick;                      // id 2
int liftStarts;  // lift's and crane's (test_mission_seq.cpp)
bool startLift(uint8_t) {
  ++liftStarts;
  return true;
}
void cancelLift() {}
HUBWIRE_CHANNELS(lone, "lone", mission("lift", lift, startLift, cancelLift), event("tick", tick));

const ChannelTable& loneTable() { return lone; }
