// Hubwire: declare a sketch's channels in a few lines; a hub (Raspberry Pi, Jetson, PC) discovers
// them over the serial line and sees typed values, controls, actions, events and streams.
//
//   #include <Hubwire.h>
//
//   Hubwire hub(Serial);
//   float speed;                      // readable and writable by the hub
//   hubwire::Event<bool> bumper;      // the hub is told exactly once per emit()
//
//   void stopMotors() { /* the hub went silent: speed is already 0 (its failsafe) */ }
//
//   HUBWIRE_CHANNELS(channels, "rover",   // at file scope: worked out when the sketch compiles
//     expose("speed", speed).writable().range(-1.0f, 1.0f).unit("m/s").failsafe(0.0f),
//     event("bumper", bumper));
//
//   void setup() {
//     Serial.begin(115200);
//     hub.onLinkLost(stopMotors);
//     hub.begin(channels);
//   }
//   void loop() {
//     hub.update();                   // never blocks
//     if (digitalRead(2) == LOW) hub.emit(bumper, true);
//   }
//
// HUBWIRE_CHANNELS turns the declarations into the descriptor JSON and one record per channel,
// constants in flash (text.h says how, board by board), so a channel costs no RAM and a wrong
// declaration fails to compile. The declarations and their options are in
// src/hubwire/channels/dsl.h (declare.h gathers them); the session is src/hubwire/session/session.h
// (class hubwire::Session, which Hubwire extends); the protocol is in docs/PROTOCOL.md.
// The hub's own channels: remote(), hub.request() / write() / call() (docs/SKETCH.md).
#ifndef HUBWIRE_H
#define HUBWIRE_H

#include <Arduino.h>

#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"  // with hubwire::Port, the binding (hubwire/port_arduino.h)

namespace hubwire {

/// Seeds the session nonce: differs between resets (a counter that survives them) and, where the
/// board has one, comes from a hardware RNG. See Session::begin().
///   session.begin(channels, hubwire::bootNonce());
uint32_t bootNonce();

}  // namespace hubwire

class Hubwire : public hubwire::Session {
 public:
  /// A hub link over any Stream: Serial, Serial1, SoftwareSerial, a USB CDC port, a WiFi client.
  ///   Hubwire hub(Serial);
  explicit Hubwire(Stream& stream) : hubwire::Session(hubwire::Port(stream)) {}  // the session keeps the Port
  // One Hubwire per Stream: a copy would share the Stream and answer the hub twice.
  Hubwire(const Hubwire&) = delete;
  Hubwire& operator=(const Hubwire&) = delete;

  /// Starts talking, with the channels HUBWIRE_CHANNELS declared; false for an empty table.
  ///   void setup() { Serial.begin(115200); hub.begin(channels); }
  bool begin(const hubwire::ChannelTable& channels) { return hubwire::Session::begin(channels, hubwire::bootNonce()); }
};

#endif
