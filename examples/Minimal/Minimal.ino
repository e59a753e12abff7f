// Minimal: the smallest useful Hubwire sketch.
//
// It offers the hub three channels:
//   blink_ms  a value the hub can read and change (how fast the LED blinks)
//   led       a control: the hub switches the LED blinking on or off
//   button    an event: the hub hears about every press of a button on pin 2, exactly once
//
// Upload it, then on the hub:  hubwire info /dev/ttyACM0
//                              hubwire set /dev/ttyACM0 blink_ms 100
#include <Hubwire.h>

Hubwire hub(Serial);

// Its values and their declarations as channels, in a header of their own (the lower-bound
// benchmarks in extras/bench/lowerbound build on the very same values).
#include "channels.h"

void setBlinking(bool on) { blinking = on; }

void setup() {
  Serial.begin(115200);
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(2, INPUT_PULLUP);
  hub.begin(channels);
}

void loop() {
  hub.update();  // answers the hub; never blocks

  static uint32_t toggledAt;
  if (millis() - toggledAt >= blinkMs) {
    toggledAt = millis();
    digitalWrite(LED_BUILTIN, blinking && !digitalRead(LED_BUILTIN));
  }

  static bool wasPressed;
  static uint8_t presses;
  bool pressed = digitalRead(2) == LOW;
  if (pressed && !wasPressed) hub.emit(button, ++presses);  // queued and retried until the hub acks
  wasPressed = pressed;
}
