// The mistakes a first sketch makes (a plant waterer, written from the README), one per
// HUBWIRE_CASE; first_sketch.sh compiles each for the Uno as the Arduino IDE does (no
// -Wfatal-errors) and checks that the whole message names the channel and the mistake in at most
// 20 lines. Case 0 must compile.
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

using namespace hubwire;

uint16_t moisture;
uint16_t threshold = 400;
char label[16];
void setPump(bool) {}
Event<uint16_t> dry;

#if HUBWIRE_CASE == 1
#define THRESHOLD expose("threshold", threshold).writable().failsafe(-1)  // a uint16_t has no -1
#elif HUBWIRE_CASE == 2
#define THRESHOLD expose("threshold", threshold).writable().range(100, 900).failsafe(50)
#elif HUBWIRE_CASE == 3
#define THRESHOLD expose("threshold", threshold).writable().range(-5, 900)
#elif HUBWIRE_CASE == 4
#define THRESHOLD expose("threshold", threshold).writable().failsafe(1.5)
#elif HUBWIRE_CASE == 5
#define THRESHOLD expose("moisture", threshold)  // the name again
#elif HUBWIRE_CASE == 6
#define THRESHOLD expose("label", label).range(0, 1)  // a string has no range
#elif HUBWIRE_CASE == 7
#define THRESHOLD expose("dry level", threshold)  // no spaces in names
#else
#define THRESHOLD expose("threshold", threshold).writable().range(100, 900).failsafe(400)
#endif

HUBWIRE_CHANNELS(channels, device("plant"),
  expose("moisture", moisture).unit("raw"),
  THRESHOLD,
  control("pump", setPump),
  event("dry", dry));
