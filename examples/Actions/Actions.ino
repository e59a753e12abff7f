// Actions: functions the hub can call.
//
//   control(name, fn)  the hub writes a value and fn receives it: a command without a result. If
//                      fn returns bool, returning false refuses the value: the hub gets an error.
//   action(name, fn)   the hub calls fn, with or without an argument, and gets its return value.
//
// Each call runs exactly once even when the serial line loses the answer and the hub asks again:
// the board recognises the repeat and answers it without calling fn a second time.
//
// Try it on the hub:  hubwire set /dev/ttyACM0 blink 3
//                     hubwire call /dev/ttyACM0 read_pin 13
// or in Python:       board.blink = 3; board.read_pin(13); board.uptime_ms()
#include <Hubwire.h>

Hubwire hub(Serial);

uint8_t blinksLeft;  // loop() blinks the LED this many more times
uint16_t calls;      // how many calls the sketch handled

// A control that refuses what it cannot do: more than 10 blinks.
bool blink(uint8_t times) {
  if (times > 10) return false;
  blinksLeft = times;
  ++calls;
  return true;  // the hub's call returns normally
}

// An action with an argument and a result: the level of a digital pin, or -1 for no such pin.
int8_t readPin(uint8_t pin) {
  ++calls;
  if (pin >= NUM_DIGITAL_PINS) return -1;
  return digitalRead(pin) == HIGH ? 1 : 0;
}

// An action without an argument.
uint32_t uptimeMs() { return millis(); }

HUBWIRE_CHANNELS(channels, "actions",
  control("blink", blink).describe("blink the LED 0..10 times"),
  action("read_pin", readPin).describe("1 high, 0 low, -1 no such pin"),
  action("uptime_ms", uptimeMs).unit("ms"),
  expose("calls", calls));

void setup() {
  Serial.begin(115200);
  pinMode(LED_BUILTIN, OUTPUT);
  hub.begin(channels);
}

void loop() {
  hub.update();
  // Called functions should return at once; longer work continues here, a step per pass.
  static uint32_t changedAt;
  if (blinksLeft && millis() - changedAt >= 150) {
    changedAt = millis();
    bool on = digitalRead(LED_BUILTIN) == HIGH;
    digitalWrite(LED_BUILTIN, on ? LOW : HIGH);
    if (on) --blinksLeft;  // a blink ends when the LED goes off
  }
}
