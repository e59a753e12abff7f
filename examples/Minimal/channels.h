// Minimal's values and the channels they are, included by Minimal.ino (and by the lower-bound
// benchmarks in extras/bench/lowerbound, which run Minimal's loop on the same values). The
// function the declarations name is defined by the sketch that includes this.
#ifndef MINIMAL_CHANNELS_H
#define MINIMAL_CHANNELS_H

#include <Hubwire.h>

uint16_t blinkMs = 500;         // the hub may set 50..5000 ms
bool blinking = true;           // changed through the "led" control
hubwire::Event<uint8_t> button; // carries how many presses so far

void setBlinking(bool on);

// The device's name and its channels, worked out when the sketch compiles: names, units and the
// descriptor the hub reads all live in flash, and a mistake here is a compile error.
HUBWIRE_CHANNELS(channels, "minimal",
  expose("blink_ms", blinkMs).writable().range(50, 5000).unit("ms"),
  control("led", setBlinking),
  event("button", button));

#endif
