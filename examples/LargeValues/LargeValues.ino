// LargeValues: values longer than one frame, and lists whose length changes.
//
//   a 200-byte struct  read and written as a whole: the hub splits a write into fragments and the
//                      board reassembles it in one buffer before checking and applying it (the
//                      buffer is sized by the compiler to the largest such value: 200 bytes here);
//                      a read goes back in fragments straight from the variable, never torn.
//   a List             hubwire::List<int16_t, 12>: up to 12 elements, carried with their count.
//   an action          taking a List: the hub passes a Python list.
//
// Try it on the hub:  hubwire get /dev/ttyACM0 profile
// or in Python:       board.path = [10, -20, 30]; board.profile = {...}; board.call("sum", [1, 2, 3])
#include <Hubwire.h>

Hubwire hub(Serial);

// 200 bytes on every board (no padding: each field is aligned already).
struct Profile {
  float gain[20];      // 80 bytes
  int16_t table[40];   // 80 bytes
  uint8_t name[40];    // 40 bytes
} profile;

hubwire::List<int16_t, 12> path;  // waypoints, cm
uint16_t profileWrites;          // writes of profile applied
uint16_t pathWrites;

void profileChanged() { ++profileWrites; }
void pathChanged() { ++pathWrites; }

uint16_t sum(const hubwire::List<uint8_t, 16>& v) {
  uint16_t s = 0;
  for (uint8_t i = 0; i < v.size(); ++i) s += v[i];
  return s;
}

HUBWIRE_CHANNELS(channels, "large",
  expose("profile", profile, "gain:f32[20],table:i16[40],name:u8[40]").writable().onChange(profileChanged),
  expose("path", path).writable().range(-1000, 1000).unit("cm").onChange(pathChanged),
  action("sum", sum),
  expose("profile_writes", profileWrites),
  expose("path_writes", pathWrites));

void setup() {
  for (uint8_t i = 0; i < 20; ++i) profile.gain[i] = i * 0.5f;
  for (uint8_t i = 0; i < 40; ++i) profile.table[i] = (int16_t)(i * 100 - 2000);
  for (uint8_t i = 0; i < 40; ++i) profile.name[i] = (uint8_t)('a' + i % 26);
  path.push(0);
  path.push(50);
  Serial.begin(115200);
  hub.begin(channels);
}

void loop() {
  hub.update();
}
