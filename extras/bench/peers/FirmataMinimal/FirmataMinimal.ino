// Hubwire's examples/Minimal written with the Firmata library, as its simple examples
// (SimpleDigitalFirmata, EchoString) would have it; built by bench/peers.sh for the like-for-like
// rows of bench/PEERS.md.
//
//   blink_ms  a user-defined sysex command (0x01; Firmata keeps 0x00..0x0F for them): empty, it
//             reads; with blink_ms (two bytes, low first), it writes. Answered by sysex 0x01
//             [ok, low, high] with blink_ms now (ok 0: the write was out of 50..5000, or malformed).
//             Every byte after the command travels as two 7-bit bytes, as sendSysex() sends them.
//   led       the standard digital message: writing pin 13 (LED_BUILTIN) switches the blinking
//             (no answer: Firmata does not answer a digital write)
//   button    the standard digital report of port 0 whenever pin 2 changes (pressed reads 0)
#include <Firmata.h>

const byte BLINK_MS = 0x01;

uint16_t blinkMs = 500;
bool blinking = true;

void sysexCallback(byte command, byte argc, byte *argv)
{
  if (command != BLINK_MS)
    return;
  byte ok = argc == 0;
  if (argc == 4) {
    uint16_t ms = word(argv[2] | argv[3] << 7, argv[0] | argv[1] << 7);
    if (ms >= 50 && ms <= 5000) {
      blinkMs = ms;
      ok = 1;
    }
  }
  byte answer[] = {ok, lowByte(blinkMs), highByte(blinkMs)};
  Firmata.sendSysex(BLINK_MS, sizeof(answer), answer);
}

void digitalWriteCallback(byte port, int value)
{
  if (port == LED_BUILTIN / 8)
    blinking = value & (1 << (LED_BUILTIN % 8));
}

void setup()
{
  Firmata.setFirmwareVersion(FIRMATA_FIRMWARE_MAJOR_VERSION, FIRMATA_FIRMWARE_MINOR_VERSION);
  Firmata.attach(START_SYSEX, sysexCallback);
  Firmata.attach(DIGITAL_MESSAGE, digitalWriteCallback);
  Firmata.begin(57600);
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(2, INPUT_PULLUP);
}

void loop()
{
  while (Firmata.available())
    Firmata.processInput();

  static uint32_t toggledAt;
  if (millis() - toggledAt >= blinkMs) {
    toggledAt = millis();
    digitalWrite(LED_BUILTIN, blinking && !digitalRead(LED_BUILTIN));
  }

  static bool wasPressed;
  bool pressed = digitalRead(2) == LOW;
  if (pressed != wasPressed)
    Firmata.sendDigitalPort(0, readPort(0, 1 << 2));
  wasPressed = pressed;
}
