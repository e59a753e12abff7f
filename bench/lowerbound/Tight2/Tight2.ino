// Tight2: Tight with the descriptor JSON generated on the board from run-time declarations
// (replayed like the current library does), instead of a compile-time flash blob. Channel
// dispatch still uses the flash table (as in Tight), so the difference is the JSON writer.
#include "decl.h"

TwHub hub;

uint16_t blinkMs = 500;
bool blinking = true;
TwEvent<uint8_t> button;

void setBlinking(bool on) { blinking = on; }

void channels() {
  hub.expose(F("blink_ms"), blinkMs).writable().range(50, 5000).unit(F("ms"));
  hub.control(F("led"), setBlinking);
  hub.event(F("button"), button);
}

static bool blinkInRange(const uint8_t* v) {
  uint16_t x;
  memcpy(&x, v, 2);
  return x >= 50 && x <= 5000;
}
static bool ledCall(const uint8_t* v) {
  setBlinking(*v);
  return true;
}
const TwChannel twChannels[] PROGMEM = {
    {(uint8_t*)&blinkMs, nullptr, blinkInRange, nullptr, TW_R | TW_W, 2},
    {nullptr, ledCall, nullptr, nullptr, TW_W, 1 | TW_BOOL},
    {nullptr, nullptr, nullptr, nullptr, TW_E, 1},
};
const uint8_t twChannelCount = 3;

void setup() {
  Serial.begin(115200);
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(2, INPUT_PULLUP);
  hub.begin(F("minimal"), channels);
}

void loop() {
  hub.update();

  static uint32_t toggledAt;
  if (millis() - toggledAt >= blinkMs) {
    toggledAt = millis();
    digitalWrite(LED_BUILTIN, blinking && !digitalRead(LED_BUILTIN));
  }

  static bool wasPressed;
  static uint8_t presses;
  bool pressed = digitalRead(2) == LOW;
  if (pressed && !wasPressed) hub.emit(button, ++presses);
  wasPressed = pressed;
}
