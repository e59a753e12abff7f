// The tests' binding of the core's seam (src/hubwire/port.h) to FakeStream and FakeClock.
#include "fakes.h"

namespace hubwire {

int portRead(Port& p) { return p.stream.read(); }
void portWrite(Port& p, const uint8_t* data, size_t len) { p.stream.write(data, len); }
size_t portWritable(Port& p) { return p.stream.room; }
uint32_t portMillis(Port& p) { return p.clock.now; }
uint32_t portMicros(Port& p) { return p.clock.micros(); }
uint8_t portBoardId(Port& p, uint8_t* out) {
  size_t n = p.stream.boardId.size() < 16 ? p.stream.boardId.size() : 16;
  for (size_t i = 0; i < n; ++i) out[i] = p.stream.boardId[i];
  return (uint8_t)n;
}

}  // namespace hubwire
