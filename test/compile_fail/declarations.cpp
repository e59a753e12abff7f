// Declarations the library must refuse when the sketch compiles, one per HUBWIRE_CASE; CMakeLists.txt
// compiles each case and expects the compiler's message to say why. Case 0 is the control: the same
// file with correct declarations must compile.
#include "hubwire/session/device.h"

using namespace hubwire;

struct Wide {
  uint8_t b[HUBWIRE_MAX_PAYLOAD];
};
uint8_t big[HUBWIRE_MAX_PAYLOAD - 1];
uint8_t fits[HUBWIRE_MAX_PAYLOAD - 2];
uint64_t wide;
Wide wideStruct;
char longText[HUBWIRE_MAX_PAYLOAD - 1];
char text[HUBWIRE_MAX_PAYLOAD - 2];
Event<uint32_t> fourBytes;
int32_t answer(int16_t v) { return v; }
uint64_t wideAnswer() { return 0; }

void setLevel(uint8_t) {}
void changed() {}

void declarations(Device& d) {
  d.control("level", setLevel).range(1, 9).failsafe(1).unit("%").describe("a control's options");
  d.expose("fits", fits);
  d.expose("text", text);
  d.event("e", fourBytes);
  d.action("answer", answer).range(-5, 5);
#if HUBWIRE_CASE == 1
  d.expose("big", big);
#elif HUBWIRE_CASE == 2
  d.expose("wide", wide);
#elif HUBWIRE_CASE == 3
  d.expose("s", wideStruct, "b:u8[32]");
#elif HUBWIRE_CASE == 4
  d.expose("s", longText);
#elif HUBWIRE_CASE == 5
  d.action("wide", wideAnswer);
#elif HUBWIRE_CASE == 6
  d.expose("s", text).range(0, 1);  // strings have no range
#elif HUBWIRE_CASE == 9
  d.event("e2", fourBytes).writable();  // nothing to write into
#elif HUBWIRE_CASE == 10
  d.control("c", setLevel).streamable();  // nothing to read
#elif HUBWIRE_CASE == 11
  d.control("c", setLevel).onChange(changed);  // would replace the control's function
#elif HUBWIRE_CASE == 12
  d.action("a", answer).failsafe(0);  // calling an action on link loss is not a failsafe
#elif HUBWIRE_CASE == 13
  d.action("a", answer).writable();
#endif
}
