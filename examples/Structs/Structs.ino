// Structs: values with several parts, as one channel each.
//
//   a struct  with named, typed fields, read (and written, and streamed) as a whole, so the hub
//             never sees half of an update. The layout text names each field and gives its type,
//             in the order of the struct; the compiler checks it against the struct: a layout
//             that is malformed or whose size differs from the struct's does not build ("struct
//             layout does not match the struct"), so a wrong one never reaches the board.
//   an array  of one type, fixed length: int16_t t[3] is i16 with 3 elements.
//   a string  in a char array: up to its size - 1 characters; the hub cannot write longer ones.
//
// Field types: bool u8 i8 u16 i16 u32 i32 f32 (f64 on 32-bit boards), arrays as name:type[n].
//
// Try it on the hub:  hubwire get /dev/ttyACM0 gps
//                     hubwire set /dev/ttyACM0 label "bench 2"
// or in Python:       board.gps.lat, board.temps[0], board.label = "bench 2"
#include <Hubwire.h>

Hubwire hub(Serial);

struct Gps {
  float lat, lon;      // degrees
  int16_t altitude;    // m
  uint8_t satellites;
  bool fix;
} gps = {52.52f, 13.405f, 34, 7, true};  // a stand-in: feed it from your GPS library

int16_t temps[3] = {215, 220, 198};  // three sensors, in tenths of a degree
char label[21] = "bench 1";          // up to 20 characters, the hub may rename the board

HUBWIRE_CHANNELS(channels, "structs",
  expose("gps", gps, "lat:f32,lon:f32,altitude:i16,satellites:u8,fix:bool").streamable(),
  expose("temps", temps).streamable().unit("0.1 C"),
  expose("label", label).writable());

void setup() {
  Serial.begin(115200);
  hub.begin(channels);
}

void loop() {
  hub.update();
}
