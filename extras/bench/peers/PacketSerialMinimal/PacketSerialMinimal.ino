// Hubwire's examples/Minimal written with PacketSerial (COBS framing), as its README and examples
// would have it; built by bench/peers.sh for the like-for-like rows of bench/PEERS.md.
//
// Packets (the first byte says what a packet is; the format is the sketch's own):
//   host -> device  'r'                  read blink_ms        -> 'v' lo hi
//                   'w' lo hi            write blink_ms       -> 'a' (taken) or 'n' (out of 50..5000)
//                   'l' on               switch the blinking  -> 'a'
//   device -> host  'b' presses          a press of the button on pin 2 (sent once, never repeated)
// Anything else, or a packet of the wrong length, is answered 'n'.
#include <PacketSerial.h>

PacketSerial myPacketSerial;

uint16_t blinkMs = 500;
bool blinking = true;

void onPacketReceived(const uint8_t* buffer, size_t size)
{
  uint8_t answer = 'n';
  if (size == 1 && buffer[0] == 'r') {
    uint8_t value[] = {'v', uint8_t(blinkMs), uint8_t(blinkMs >> 8)};
    myPacketSerial.send(value, sizeof(value));
    return;
  }
  if (size == 3 && buffer[0] == 'w') {
    uint16_t ms = buffer[1] | (buffer[2] << 8);
    if (ms >= 50 && ms <= 5000) {
      blinkMs = ms;
      answer = 'a';
    }
  } else if (size == 2 && buffer[0] == 'l') {
    blinking = buffer[1] != 0;
    answer = 'a';
  }
  myPacketSerial.send(&answer, 1);
}

void setup()
{
  myPacketSerial.begin(115200);
  myPacketSerial.setPacketHandler(&onPacketReceived);
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(2, INPUT_PULLUP);
}

void loop()
{
  myPacketSerial.update();

  static uint32_t toggledAt;
  if (millis() - toggledAt >= blinkMs) {
    toggledAt = millis();
    digitalWrite(LED_BUILTIN, blinking && !digitalRead(LED_BUILTIN));
  }

  static bool wasPressed;
  static uint8_t presses;
  bool pressed = digitalRead(2) == LOW;
  if (pressed && !wasPressed) {
    uint8_t event[] = {'b', ++presses};
    myPacketSerial.send(event, sizeof(event));
  }
  wasPressed = pressed;
}
