// Tight: examples/Minimal with a size-first device implementation (tight.h/.cpp) instead of
// Hubwire's session. The descriptor and channel table below, written by hand, are what
// HUBWIRE_CHANNELS builds from Minimal's declarations (checked: same length and hash):
//   expose("blink_ms", blinkMs).writable().range(50, 5000).unit("ms"),
//   control("led", setBlinking),
//   event("button", button)
#include "tight.h"

// Minimal's values, and its declarations that the descriptor below is checked against, from
// examples/Minimal/channels.h (the build passes -I examples/Minimal). Nothing of the library is
// linked: the declarations' tables are never referenced, so they are left out.
#include "channels.h"

void setBlinking(bool on) { blinking = on; }

// TIGHT_STREAMABLE: blink_ms also streamable ("rws"), to exercise S/D against the hub.
#ifdef TIGHT_STREAMABLE
#define TW_BLINK_ACCESS "rws"
#define TW_BLINK_BITS (TW_R | TW_W | TW_S)
#else
#define TW_BLINK_ACCESS "rw"
#define TW_BLINK_BITS (TW_R | TW_W)
#endif

#define TW_JSON                                                                                  \
  "{\"p\":1,\"n\":\"minimal\",\"ch\":[{\"id\":1,\"n\":\"blink_ms\",\"a\":\"" TW_BLINK_ACCESS      \
  "\",\"t\":\"u16\",\"u\":\"ms\",\"min\":50,\"max\":5000},{\"id\":2,\"n\":\"led\",\"a\":\"w\","    \
  "\"t\":\"bool\"},{\"id\":3,\"n\":\"button\",\"a\":\"e\",\"t\":\"u8\"}]}"

#ifndef TIGHT_STREAMABLE
static_assert(sizeof(TW_JSON) - 1 == channels.jsonLength && twFnv(TW_JSON, sizeof(TW_JSON) - 1) == channels.hash,
              "the descriptor written here is not the one examples/Minimal's declarations make");
#endif

const char twDescriptor[] PROGMEM = TW_JSON;
const uint16_t twDescLength = sizeof(TW_JSON) - 1;
const uint8_t twHelloTail[10] PROGMEM = {TW_U16(TW_MAX_PAYLOAD), TW_U16(TW_HEARTBEAT_MS),
                                          TW_U32(twFnv(TW_JSON, sizeof(TW_JSON) - 1)),
                                          TW_U16(sizeof(TW_JSON) - 1)};

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
    {(uint8_t*)&blinkMs, nullptr, blinkInRange, nullptr, TW_BLINK_BITS, 2},
    {nullptr, ledCall, nullptr, nullptr, TW_W, 1 | TW_BOOL},
    {nullptr, nullptr, nullptr, nullptr, TW_E, 1},
};
const uint8_t twChannelCount = sizeof(twChannels) / sizeof(twChannels[0]);
const uint8_t kButton = 3;

void setup() {
  Serial.begin(115200);
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(2, INPUT_PULLUP);
  twBegin();
}

void loop() {
  twUpdate();  // answers the hub; never blocks

  static uint32_t toggledAt;
  if (millis() - toggledAt >= blinkMs) {
    toggledAt = millis();
    digitalWrite(LED_BUILTIN, blinking && !digitalRead(LED_BUILTIN));
  }

  static bool wasPressed;
  static uint8_t presses;
  bool pressed = digitalRead(2) == LOW;
  if (pressed && !wasPressed) {
    ++presses;
    twEmit(kButton, &presses, 1);  // queued and retried until the hub acks
  }
  wasPressed = pressed;
}
