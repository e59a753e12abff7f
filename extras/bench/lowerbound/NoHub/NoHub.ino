// Minimal's own loop without any hub: what the sketch part of Minimal costs by itself. Its values
// come from examples/Minimal/channels.h (the build passes -I examples/Minimal); the declarations
// there are never referenced, so nothing of the library is linked.
#include "channels.h"

void setBlinking(bool on) { blinking = on; }
volatile uint8_t sink;
void setup() {
  Serial.begin(115200);
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(2, INPUT_PULLUP);
}
void loop() {
  if (Serial.available()) Serial.write(Serial.read());
  static uint32_t toggledAt;
  if (millis() - toggledAt >= blinkMs) {
    toggledAt = millis();
    digitalWrite(LED_BUILTIN, blinking && !digitalRead(LED_BUILTIN));
  }
  static bool wasPressed;
  static uint8_t presses;
  bool pressed = digitalRead(2) == LOW;
  if (pressed && !wasPressed) sink = ++presses;
  wasPressed = pressed;
}
