// Hubwire's examples/Minimal written with SerialTransfer (framing with a CRC-8 and a packet ID), as
// its examples would have it; built by bench/peers.sh for the like-for-like rows of bench/PEERS.md.
//
// Packets, told apart by their packet ID (SerialTransfer carries no empty packet, so a read sends
// one byte that is not looked at):
//   host -> device  ID 0, any byte     read blink_ms        -> ID 0: uint16 blink_ms
//                   ID 1, uint16       write blink_ms       -> ID 1: uint8 taken (0: out of 50..5000), uint16 blink_ms
//                   ID 2, uint8 on     switch the blinking  -> ID 2: uint8 1
//   device -> host  ID 3, uint8        a press of the button on pin 2 (sent once, never repeated)
// Packets of another ID are not answered.
#include "SerialTransfer.h"

SerialTransfer myTransfer;

uint16_t blinkMs = 500;
bool blinking = true;

void setup()
{
  Serial.begin(115200);
  // The Uno's one port carries the packets: no debug messages on it.
  myTransfer.begin(Serial, false);
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(2, INPUT_PULLUP);
}

void loop()
{
  if (myTransfer.available())
  {
    uint8_t id = myTransfer.currentPacketID();
    uint16_t sendSize = 0;
    if (id == 1)
    {
      uint16_t ms;
      myTransfer.rxObj(ms);
      uint8_t taken = ms >= 50 && ms <= 5000;
      if (taken)
        blinkMs = ms;
      sendSize = myTransfer.txObj(taken, sendSize);
    }
    else if (id == 2)
    {
      uint8_t on;
      myTransfer.rxObj(on);
      blinking = on != 0;
      sendSize = myTransfer.txObj((uint8_t)1, sendSize);
    }
    if (id <= 1)
      sendSize = myTransfer.txObj(blinkMs, sendSize);
    if (sendSize)
      myTransfer.sendData(sendSize, id);
  }

  static uint32_t toggledAt;
  if (millis() - toggledAt >= blinkMs) {
    toggledAt = millis();
    digitalWrite(LED_BUILTIN, blinking && !digitalRead(LED_BUILTIN));
  }

  static bool wasPressed;
  static uint8_t presses;
  bool pressed = digitalRead(2) == LOW;
  if (pressed && !wasPressed) {
    uint16_t sendSize = myTransfer.txObj(++presses);
    myTransfer.sendData(sendSize, 3);
  }
  wasPressed = pressed;
}
