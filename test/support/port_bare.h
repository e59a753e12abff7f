// A Port of the Arduino binding's shape without Arduino.h, for compiling the core alone for a
// board's MCU (make test-avr-core): the session holds its Port by value, so it needs one.
#ifndef HUBWIRE_TEST_PORT_BARE_H
#define HUBWIRE_TEST_PORT_BARE_H

#include <stdint.h>

namespace hubwire {

class Port {
 public:
  void* stream;
  uint8_t mostRoom;
};

}  // namespace hubwire

#endif
