// Hubwire: declare a sketch's channels in a few lines; a hub (Raspberry Pi, Jetson, PC) discovers
// them over the serial line and sees typed values, controls, actions, events and streams.
//
//   #include <Hubwire.h>
//
//   Hubwire hub(Serial);
//   float speed;                      // readable and writable by the hub
//   hubwire::Event<bool> bumper;      // the hub is told exactly once per emit()
//
//   void channels() {                 // Hubwire runs this whenever it needs to know a channel
//     hub.expose(F("speed"), speed).writable().range(-1, 1).unit(F("m/s")).failsafe(0);
//     hub.event(F("bumper"), bumper);
//   }
//   void setup() {
//     Serial.begin(115200);
//     hub.onLinkLost(stopMotors);     // the hub went silent: speed is already 0 (its failsafe)
//     hub.begin(F("rover"), channels);
//   }
//   void loop() {
//     hub.update();                   // never blocks
//     if (digitalRead(2) == LOW) hub.emit(bumper, true);
//   }
//
// The declarations function is called again to describe, find and reset channels, so nothing about
// a channel is copied into RAM. Put only declarations in it. The full reference is in
// src/hubwire/session/device.h (class hubwire::Device, which Hubwire extends); the protocol is in
// docs/PROTOCOL.md.
#ifndef HUBWIRE_H
#define HUBWIRE_H

#include <Arduino.h>

#include "hubwire/session/device.h"

namespace hubwire {

// Binds the core's seams to an Arduino Stream and millis().
class ArduinoPorts : public ByteStream, public Clock {
 public:
  explicit ArduinoPorts(Stream& s) : stream_(s), reportsRoom_(false) {}
  int read() override { return stream_.read(); }
  void write(const uint8_t* data, size_t len) override { stream_.write(data, len); }
  size_t writable() override {
    int n = stream_.availableForWrite();
    if (n > 0) reportsRoom_ = true;
    // Some cores never implement availableForWrite() (always 0): then we cannot know, so go ahead.
    return reportsRoom_ ? (size_t)n : (size_t)0xFFFF;
  }
  uint32_t millis() override { return ::millis(); }
  uint32_t micros() override { return ::micros(); }

 protected:
  Stream& stream_;
  bool reportsRoom_;
};

// Seeds the session nonce: differs between resets (a counter that survives them) and, where the
// board has one, comes from a hardware RNG. See Device::begin().
uint32_t bootNonce();

}  // namespace hubwire

class Hubwire : private hubwire::ArduinoPorts, public hubwire::Device {
 public:
  // Any Stream: Serial, Serial1, SoftwareSerial, a USB CDC port, a WiFi client.
  explicit Hubwire(Stream& stream) : hubwire::ArduinoPorts(stream), hubwire::Device(*this, *this) {}

  // Checks the declarations and starts talking. false if a declaration is wrong: error() says why
  // and errorChannel() which channel (1 = the first declared).
  bool begin(hubwire::Text name, void (*declarations)(), hubwire::Text firmware = hubwire::Text()) {
    return hubwire::Device::begin(name, declarations, firmware, hubwire::bootNonce());
  }
};

#endif
