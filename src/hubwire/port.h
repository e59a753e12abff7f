// The two seams through which the portable core reaches the outside world. The Arduino face binds
// them to a Stream and millis(); tests bind them to fakes; the emulator binds them to a pty.
#ifndef HUBWIRE_PORT_H
#define HUBWIRE_PORT_H

#include <stddef.h>
#include <stdint.h>

namespace hubwire {

class ByteStream {
 public:
  // Next received byte, or -1 when none is waiting. Must not block.
  virtual int read() = 0;
  // Queue bytes for sending.
  virtual void write(const uint8_t* data, size_t len) = 0;
  // Bytes that can be written now without blocking; a large number when unknown.
  virtual size_t writable() = 0;
};

class Clock {
 public:
  // Milliseconds since some fixed point; wraps at 2^32.
  virtual uint32_t millis() = 0;
  // Microseconds, for entropy only (when the hub is first heard varies from boot to boot).
  virtual uint32_t micros() { return millis() * 1000u; }
};

}  // namespace hubwire

#endif
