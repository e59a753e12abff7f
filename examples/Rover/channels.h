// Rover's values and the channels they are, included by Rover.ino (and by the benchmark firmware
// extras/bench/RxCycles, which measures these twelve channels). The functions the declarations
// name are defined by the sketch that includes this.
#ifndef ROVER_CHANNELS_H
#define ROVER_CHANNELS_H

#include <Hubwire.h>

float left, right;  // motor speeds in m/s, -1..1

struct Imu {
  float ax, ay, az;  // m/s^2
  int16_t gyro[3];   // deg/s
} imu;

uint16_t rangeCm[4];     // front, right, back, left
uint16_t batteryMv = 7400;
bool led;
char name[17] = "rover";  // up to 16 characters

hubwire::Event<bool> bumper;  // true when pressed, false when released

uint16_t failsafes;  // how often the hub went silent
uint32_t applied;    // writes applied from the hub (each exactly once)

void countWrite();
void ledChanged();
bool beep(uint16_t ms);
uint8_t selftest(uint8_t count);

// The device and its channels, worked out when the sketch compiles: names, units and the
// descriptor stay in flash, and a mistake here is a compile error. The list comes after everything
// it names. selftest emits bumper through its handle alone; begin() gives the event its id.
HUBWIRE_CHANNELS(channels, device("rover").firmware("1.0.0"),
  expose("left", left).writable().streamable().range(-1.0f, 1.0f).unit("m/s").failsafe(0.0f).onChange(countWrite),
  expose("right", right).writable().streamable().range(-1.0f, 1.0f).unit("m/s").failsafe(0.0f).onChange(countWrite),
  expose("imu", imu, "ax:f32,ay:f32,az:f32,gyro:i16[3]").streamable().describe("accel m/s2, gyro deg/s"),
  expose("range", rangeCm).streamable().unit("cm"),
  expose("battery", batteryMv).streamable().unit("mV"),
  expose("led", led).writable().onChange(ledChanged),
  expose("name", name).writable().onChange(countWrite),
  event("bumper", bumper),
  action("beep", beep).describe("beep for ms (max 2000)"),
  action("selftest", selftest).describe("emit n bumper events"),
  expose("failsafes", failsafes),
  expose("applied", applied));

#endif
