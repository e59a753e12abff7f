// Stand-in sketch for tools/arm-check/check-arm.sh: the Arduino face of Hubwire, compiled for
// Cortex-M against the Arduino.h stand-in. It exercises the public API the examples use:
// writable values with range/unit/failsafe, arrays, bounded strings, struct layouts, events,
// controls and actions, lists and a value larger than a frame (fragments), declared with HUBWIRE_CHANNELS: the descriptor and the records are worked
// out by the ARM compiler, the struct layout checked against this target's alignment.
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
double precise;  // f64: double is 8 bytes on Cortex-M
hubwire::Event<bool> bumper;
hubwire::List<float, 16> path;
struct Map {  // 3 bytes of padding after `rows` on this target, 261 on the wire
  uint8_t rows;
  float cells[64];
  uint32_t stamp;
} map;

static void stopMotors() { speed = 0; }
static void setLed(bool on) { counter = on ? 1 : 0; }
static bool beep(uint16_t ms) { return ms < 2000; }
static uint8_t selftest(uint8_t n) { return hub.emit(bumper, n % 2 == 0) ? n : 0; }
static uint8_t count(const hubwire::List<int16_t, 32>& v) { return v.size(); }

HUBWIRE_CHANNELS(channels, device("rover").firmware("0.1.0"),
  expose("speed", speed).writable().range(-1.0f, 1.0f).unit("m/s").failsafe(0.0f),
  expose("counter", counter).streamable(),
  expose("ranges", ranges).streamable().unit("cm"),
  expose("label", label).writable(),
  expose("imu", imu, "ax:f32,ay:f32,az:f32,gyro:i16[3]").streamable().describe("imu"),
  expose("precise", precise).range(-1e6, 1e6),
  event("bumper", bumper),
  control("led", setLed),
  action("beep", beep),
  action("selftest", selftest),
  expose("path", path).writable().range(-10.0f, 10.0f),
  expose("map", map, "rows:u8,cells:f32[64],stamp:u32").writable().streamable(),
  action("count", count));

void setup() {
  Serial.begin(115200);
  hub.onLinkLost(stopMotors);
  hub.begin(channels);
}

void loop() {
  counter++;
  hub.update();
}
