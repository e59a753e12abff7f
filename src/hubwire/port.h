// The seam through which the portable core reaches the outside world: a byte stream and a clock.
// Each program links exactly one binding that defines class Port and the functions below: the
// Arduino face binds them to a Stream and millis() (port_arduino.h, src/HubwireArduino.cpp), tests
// to fakes (test/support), the fuzzers to their input. Plain functions bound at link time, not
// virtual ones: AVR keeps vtables in RAM and pays an indirect call per byte. The session holds its
// Port by value (one load fewer per use than through a reference: Uno flash -26 B in Minimal), so
// the binding's header is included here: HUBWIRE_PORT_HEADER where the build names one, else the
// Arduino binding's. A Port is copied into the session: it refers to its stream, not owns it.
#ifndef HUBWIRE_PORT_H
#define HUBWIRE_PORT_H

#include <stddef.h>
#include <stdint.h>

namespace hubwire {

class Port;  // defined by the binding

}  // namespace hubwire

#if defined(HUBWIRE_PORT_HEADER)
#include HUBWIRE_PORT_HEADER
#elif defined(ARDUINO)
#include "port_arduino.h"
#endif

namespace hubwire {

// Next received byte, or -1 when none is waiting. Must not block.
int portRead(Port& port);
// Queue bytes for sending.
void portWrite(Port& port, const uint8_t* data, size_t len);
// Bytes that can be written now without blocking; a large number when unknown, or when waiting
// cannot make more room (the transmit buffer is as empty as it gets).
size_t portWritable(Port& port);
// Milliseconds since some fixed point; wraps at 2^32.
uint32_t portMillis(Port& port);
// Microseconds, or any count that runs as fast, for entropy only (when the hub is first heard
// varies from boot to boot).
uint32_t portMicros(Port& port);
// This board's id, which tells two boards running the same sketch apart (PROTOCOL 3.4, `R` id 0):
// writes 1..16 bytes to out and returns how many, or returns 0 when the board has none.
uint8_t portBoardId(Port& port, uint8_t* out);

}  // namespace hubwire

#endif
