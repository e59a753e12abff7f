// Rover: a small robot with two motors, an IMU, range sensors, a bumper, an LED and a buzzer,
// steered from a Raspberry Pi (or any hub) over USB serial.
//
// What it shows:
//   - writable values with ranges and units, and a failsafe: if the hub goes silent, both motors
//     are set to 0 before onLinkLost() runs (the hub sees "failsafes" count up);
//   - a struct channel (imu) with named fields, a fixed array (range), a bounded string (name);
//   - streamable sensors: the hub subscribes, e.g. `hubwire watch /dev/ttyACM0`;
//   - an event (bumper) delivered exactly once, and callable actions with an argument and a result.
//
// The sensors here are stand-ins computed from the motor speeds, so the sketch runs on a bare
// board (and in the simulator); replace readSensors() with your IMU and sonar libraries.
#include <Hubwire.h>

Hubwire hub(Serial);

const uint8_t kLeftMotorPin = 5, kRightMotorPin = 6, kBumperPin = 2, kBuzzerPin = 8;

// Its values and their declarations as channels, in a header of their own so that the benchmark
// firmware (extras/bench/RxCycles) measures these very channels.
#include "channels.h"

// onChange also runs when the failsafe sets left and right on link loss, with the link already
// down: only writes from the hub are counted.
void countWrite() {
  if (hub.linked()) ++applied;
}

void ledChanged() {
  digitalWrite(LED_BUILTIN, led ? HIGH : LOW);
  ++applied;
}

// Callable actions: the hub passes an argument and gets the return value back.
bool beep(uint16_t ms) {
  if (ms > 2000) return false;  // refuse long beeps
  tone(kBuzzerPin, 880, ms);
  return true;
}

// Queues `count` bumper events (pressed, released, ...) to test the event path from the hub.
uint8_t selftest(uint8_t count) {
  uint8_t queued = 0;
  for (uint8_t i = 0; i < count; ++i)
    if (hub.emit(bumper, i % 2 == 0)) ++queued;
  return queued;
}

void stopMotors() {
  ++failsafes;  // left and right are already 0: their failsafe values were applied first
  analogWrite(kLeftMotorPin, 0);
  analogWrite(kRightMotorPin, 0);
}


void readSensors() {
  static uint32_t at;
  if (millis() - at < 20) return;
  at = millis();
  float turn = left - right, drive = (left + right) / 2;
  imu.ax = drive * 0.5f;
  imu.ay = turn * 0.2f;
  imu.az = 9.81f;
  imu.gyro[2] = (int16_t)(turn * 90);
  // Obstacles come nearer ahead while it drives forward, and on the side it turns towards.
  int16_t ahead = (int16_t)(drive * 100), side = (int16_t)(turn * 50);
  rangeCm[0] = (uint16_t)(150 - ahead);
  rangeCm[1] = (uint16_t)(150 - side);
  rangeCm[2] = (uint16_t)(150 + ahead);
  rangeCm[3] = (uint16_t)(150 + side);
  batteryMv = (uint16_t)(7400 - (fabs(left) + fabs(right)) * 150);  // sags under load
}

void setup() {
  Serial.begin(115200);
  pinMode(LED_BUILTIN, OUTPUT);
  pinMode(kBumperPin, INPUT_PULLUP);
  hub.onLinkLost(stopMotors);
  hub.begin(channels);
}

void loop() {
  hub.update();
  readSensors();

  analogWrite(kLeftMotorPin, (uint8_t)(fabs(left) * 255));
  analogWrite(kRightMotorPin, (uint8_t)(fabs(right) * 255));

  static bool wasPressed;
  bool pressed = digitalRead(kBumperPin) == LOW;
  if (pressed != wasPressed && hub.emit(bumper, pressed)) wasPressed = pressed;
}
