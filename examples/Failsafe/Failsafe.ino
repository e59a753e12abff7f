// Failsafe: stop the motor when the hub goes silent.
//
// A robot must not keep driving when the computer steering it crashes, hangs or is unplugged.
// Hubwire listens for the hub's heartbeats. After a few missed ones (about 1 s with the default
// hub) it declares the link lost and then, in this order:
//   1. sets every channel that declared a failsafe value to that value (speed -> 0 here) and
//      calls its onChange, as a write from the hub would: driveMotor() stops the motor;
//   2. calls the function given to onLinkLost(), where you stop what the values alone do not.
// When a hub talks to the board again, onLinkUp() runs and the hub can drive again.
//
// Try it on the hub:  hubwire set /dev/ttyACM0 speed 50
//                     then stop the hub (Ctrl-C a script, unplug it): the motor stops within ~1 s
//                     hubwire get /dev/ttyACM0 stops      how often that happened
#include <Hubwire.h>

Hubwire hub(Serial);

const uint8_t kMotorPwmPin = 5;  // PWM input of a motor driver
const uint8_t kMotorDirPin = 4;  // its direction input

int16_t speed;   // percent, -100..100, written by the hub
uint16_t stops;  // how often the failsafe stopped the motor

// Runs after every write from the hub and after the failsafe (onChange): the pins follow speed.
void driveMotor() {
  digitalWrite(kMotorDirPin, speed < 0 ? HIGH : LOW);
  analogWrite(kMotorPwmPin, (uint8_t)((uint16_t)abs(speed) * 255 / 100));
}

void linkLost() {
  // speed already holds its failsafe value, 0, and driveMotor() has passed it on to the driver.
  ++stops;
  digitalWrite(LED_BUILTIN, LOW);  // the LED shows whether a hub is in charge
}

void linkUp() { digitalWrite(LED_BUILTIN, HIGH); }

// failsafe(0): the value speed takes when the link is lost. The hub sees it in the descriptor.
HUBWIRE_CHANNELS(channels, "failsafe",
  expose("speed", speed).writable().range(-100, 100).unit("%").failsafe(0).onChange(driveMotor),
  expose("stops", stops).describe("times the failsafe stopped the motor"));

void setup() {
  Serial.begin(115200);
  pinMode(kMotorPwmPin, OUTPUT);
  pinMode(kMotorDirPin, OUTPUT);
  pinMode(LED_BUILTIN, OUTPUT);
  hub.onLinkLost(linkLost);
  hub.onLinkUp(linkUp);
  hub.begin(channels);
}

void loop() {
  hub.update();  // also where a silent hub is noticed: keep loop() free of long delays
}
