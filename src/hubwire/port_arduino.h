// The core's seam bound to an Arduino Stream (functions in HubwireArduino.cpp).
#ifndef HUBWIRE_PORT_ARDUINO_H
#define HUBWIRE_PORT_ARDUINO_H

#include <Arduino.h>

namespace hubwire {

class Port {
 public:
  /// The port over stream; Hubwire makes its own, a sketch need not.
  ///   hubwire::Port port(Serial);
  explicit Port(Stream& s) : stream(s), mostRoom(0) {}
  Stream& stream;
  uint8_t mostRoom;  // the most availableForWrite() has reported (255 and more count as 255)
};

}  // namespace hubwire

#endif
