// Stand-in sketch for tools/arm-check/check-arm.sh: the Arduino face of Hubwire, compiled for
// Cortex-M against the Arduino.h stand-in. It exercises the public API the examples use:
// writable values with range/unit/failsafe, arrays, bounded strings, struct layouts, events,
// controls and actions.
#include <Hubwire.h>

Hubwire hub(Serial);

float speed;
uint16_t counter;
int16_t ranges[4];
char label[13] = "arm";
struct Imu {
  float ax, ay, az;
  int16_t gyro[3];
} imu;
#if HUBWIRE_HAS_F64
double precise;
#endif
hubwire::Event<bool> bumper;

static void stopMotors() { speed = 0; }
static void setLed(bool on) { counter = on ? 1 : 0; }
static bool beep(uint16_t ms) { return ms < 2000; }
static uint8_t selftest(uint8_t n) { return hub.emit(bumper, n % 2 == 0) ? n : 0; }

static void channels() {
  hub.expose(F("speed"), speed).writable().range(-1, 1).unit(F("m/s")).failsafe(0);
  hub.expose(F("counter"), counter).streamable();
  hub.expose(F("ranges"), ranges).streamable().unit(F("cm"));
  hub.expose(F("label"), label).writable();
  hub.expose(F("imu"), imu, F("ax:f32,ay:f32,az:f32,gyro:i16[3]")).streamable().describe(F("imu"));
#if HUBWIRE_HAS_F64
  hub.expose(F("precise"), precise);
#endif
  hub.event(F("bumper"), bumper);
  hub.control(F("led"), setLed);
  hub.action(F("beep"), beep);
  hub.action(F("selftest"), selftest);
}

void setup() {
  Serial.begin(115200);
  hub.onLinkLost(stopMotors);
  hub.begin(F("rover"), channels, F("0.1.0"));
}

void loop() {
  counter++;
  hub.update();
}
