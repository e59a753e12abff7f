// A table with a mission and an event and no hub channels, for test_wrap_model.cpp (a file may hold
// one table with missions).
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

using namespace hubwire;

Mission<uint16_t(uint8_t), uint16_t> lift;  // id 1
Event<uint16_t> tick;                       // id 2
bool startLift(uint8_t) { return true; }
void cancelLift() {}
HUBWIRE_CHANNELS(lone, "lone", mission("lift", lift, startLift, cancelLift), event("tick", tick));

const ChannelTable& loneTable() { return lone; }
