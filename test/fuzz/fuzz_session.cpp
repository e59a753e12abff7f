// libFuzzer harness: the device session dispatcher (src/hubwire/session/session.*) fed arbitrary
// bytes through a fake stream, with a fake clock that the input advances.
//
// The Session declares channels of every kind: each scalar type (bool .. f64), a fixed array, a
// struct, a bounded string, writable/streamable/ranged/failsafe options, controls (plain and
// refusing), actions (with and without argument / return value) and three events.
//
// Input: byte 0 = mode. Mode bit 0 clear: "raw": the rest is the line, byte for byte; after every
// 0x00 the device runs update() and the clock advances by 3 ms per byte of that segment.
// Mode bit 0 set: "structured": records [dt][type][seq][id][len][payload: len % 64 bytes]; the
// harness encodes each as a valid frame (so CRC is no obstacle), advances the clock by dt * 4 ms and
// runs update() twice. dt 0xFF instead emits events (seq & 3 of them), dt 0xFE sends the record's
// payload as raw, unframed bytes. Mode bits 1..7 set the room the fake stream reports (x 4 bytes).
// At the end the clock runs on for 2 s in steps (retries, streams, link loss, announces).
//
// Checks, beyond the sanitizers: everything the device writes decodes as valid frames (no CRC,
// COBS or length error), with payloads of at most HUBWIRE_MAX_PAYLOAD bytes, and the event queue
// never holds more than HUBWIRE_EVENT_QUEUE events.
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <vector>

#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

using namespace hubwire;

#define CHECK(c)                                                          \
  do {                                                                    \
    if (!(c)) {                                                           \
      fprintf(stderr, "fuzz_session: check failed: %s (line %d)\n", #c, __LINE__); \
      abort();                                                            \
    }                                                                     \
  } while (0)

namespace {

}  // namespace

// The fuzzer's binding of the core's seam (fuzz_port.h): input from the fuzz data, a clock it advances.
int hubwire::portRead(Port& p) { return p.line.pos < p.line.in.size() ? p.line.in[p.line.pos++] : -1; }
void hubwire::portWrite(Port& p, const uint8_t* data, size_t len) { p.line.out.insert(p.line.out.end(), data, data + len); }
size_t hubwire::portWritable(Port& p) { return p.line.room; }
uint32_t hubwire::portMillis(Port& p) { return p.line.now; }
uint32_t hubwire::portMicros(Port& p) { return p.line.now * 1000u; }
uint8_t hubwire::portBoardId(Port&, uint8_t*) { return 0; }

namespace {

// channel variables
bool vBool;
uint8_t vU8;
int8_t vI8;
uint16_t vU16;
int16_t vI16;
uint32_t vU32;
int32_t vI32;
float vF32;
double vF64;
uint16_t vArr[4];
struct Imu {
  float ax;
  int16_t gyro[3];
  int16_t temp;
} vImu;
char vText[17];
List<int16_t, 8> vList;  // Lists and a value larger than a frame: fragments both ways
struct Big {
  uint8_t b[60];
  uint16_t w[10];
} vBig;
Event<bool> evBool;
Event<uint16_t> evU16;
Event<float> evF32;
uint32_t changes, calls;

void changed() { ++changes; }
void setLed(bool v) { vBool = v; }
bool setChecked(int16_t v) { return v >= 0; }
uint8_t act(uint8_t v) { ++calls; return (uint8_t)(v + 1); }
void actVoid(uint16_t v) { calls += v & 1; }
int32_t noArg() { return (int32_t)++calls; }
void plain() { ++calls; }
uint16_t listSum(const List<uint8_t, 40>& v) {
  uint16_t t = 0;
  for (uint8_t i = 0; i < v.size(); ++i) t = (uint16_t)(t + v[i]);
  return t;
}
Mission<float(float), float> drive;
Mission<void(), void> home;
bool startDrive(float g) { return g != 3.0f; }
void startHome() {}
void stopIt() { ++calls; }

}  // namespace

// At file scope, as in a sketch (the macro defines hubwire::sketchFeatures): the declarations specialise a template of the global namespace,
// which clang allows only from a namespace that encloses it.
HUBWIRE_CHANNELS(channels, device("fuzz").firmware("0.1"),
  expose("b", vBool).writable().failsafe(0).onChange(changed),
  expose("u8", vU8).writable().streamable().range(0, 200).unit("x"),
  expose("i8", vI8).writable().range(-5, 5).failsafe(-1),
  expose("u16", vU16).writable().streamable().describe("sixteen"),
  expose("i16", vI16).writable().range(-1000, 1000),
  expose("u32", vU32).writable().onChange(changed),
  expose("i32", vI32).streamable(),
  expose("f32", vF32).writable().streamable().range(-1, 1).failsafe(0).unit("m/s"),
  expose("f64", vF64).writable().range(-1e6, 1e6),
  expose("arr", vArr).writable().streamable().range(0, 5000),
  expose("imu", vImu, "ax:f32,gyro:i16[3],temp:i16").streamable(),
  expose("text", vText).writable().onChange(changed),
  expose("list", vList).writable().streamable().range(-100, 100),
  expose("big", vBig, "b:u8[60],w:u16[10]").writable().streamable().onChange(changed),
  action("listSum", listSum),
  control("led", setLed),
  control("checked", setChecked),
  action("act", act),
  action("actVoid", actVoid),
  action("noArg", noArg),
  action("plain", plain),
  event("bump", evBool),
  event("count", evU16),
  event("level", evF32),
  mission("drive", drive, startDrive, stopIt).range(0.0f, 10.0f).progressMax(10.0f),
  mission("home", home, startHome, stopIt));

namespace {

void resetState() {
  vBool = false;
  vU8 = 0;
  vI8 = 0;
  vU16 = 0;
  vI16 = 0;
  vU32 = 0;
  vI32 = 0;
  vF32 = 0;
  vF64 = 0;
  memset(vArr, 0, sizeof(vArr));
  memset(&vImu, 0, sizeof(vImu));
  vList.clear();
  memset(&vBig, 0, sizeof(vBig));
  strcpy(vText, "hello");
  changes = calls = 0;
  drive = decltype(drive)();
  home = decltype(home)();
  missionLink = MissionLink();
}

void checkOutput(FuzzLine& s) {
  static uint8_t buf[HUBWIRE_RAW_FRAME_SIZE(255)];
  FrameReceiver rx(buf, sizeof(buf));
  for (uint8_t b : s.out) {
    if (rx.feed(b)) CHECK(rx.frame().len <= HUBWIRE_MAX_PAYLOAD);
  }
  CHECK(rx.counters.crc == 0 && rx.counters.overflow == 0 && rx.counters.dropped == 0);
  CHECK(s.out.empty() || s.out.back() == 0);  // whole frames only
  s.out.clear();
}

void step(Session& d, FuzzLine& s) {
  d.update();
  CHECK(d.eventsQueued() <= HUBWIRE_EVENT_QUEUE);
  checkOutput(s);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  resetState();
  FuzzLine s;
  s.now = 1000;
  s.room = (size_t)(data[0] >> 1) * 4;
  Port port(s);
  Session d(port);
  bool ok = d.begin(channels, 0x12345678);
  CHECK(ok);
  checkOutput(s);
  if ((data[0] & 1) == 0) {  // raw
    size_t seg = 0;
    for (size_t i = 1; i < size; ++i) {
      s.in.push_back(data[i]);
      ++seg;
      if (data[i] == 0) {
        s.now += (uint32_t)(3 * seg);
        seg = 0;
        // the device reads at most 128 bytes per update: drain what is there
        while (s.pos < s.in.size()) step(d, s);
        step(d, s);
      }
    }
    while (s.pos < s.in.size()) step(d, s);
  } else {  // structured
    size_t i = 1;
    while (i + 5 <= size) {
      uint8_t dt = data[i], type = data[i + 1], seq = data[i + 2], id = data[i + 3];
      size_t len = data[i + 4] % 64;
      i += 5;
      if (len > size - i) len = size - i;
      const uint8_t* payload = data + i;
      i += len;
      if (dt == 0xFF) {
        for (uint8_t k = 0; k < (seq & 3); ++k) {
          switch ((id + k) % 3) {
            case 0: d.emit(evBool, (type & 1) != 0); break;
            case 1: d.emit(evU16, (uint16_t)(type * 257u)); break;
            default: d.emit(evF32, (float)type / 7.0f); break;
          }
          switch ((type >> 1) % 5) {  // the sketch's mission reports
            case 0: d.progress(drive, (float)seq); break;
            case 1: d.finish(drive, (float)id); break;
            case 2: d.fail(drive, (uint8_t)(type | 1)); break;
            case 3: d.progress(home); break;
            default: d.finish(home); break;
          }
        }
      } else if (dt == 0xFE) {
        s.in.insert(s.in.end(), payload, payload + len);
      } else {
        s.now += (uint32_t)dt * 4;
        uint8_t wire[FrameWriter::wireSize(255) + 8];
        size_t n = encodeFrame(type, seq, id, payload, (uint8_t)len, wire);
        s.in.insert(s.in.end(), wire, wire + n);
      }
      while (s.pos < s.in.size()) step(d, s);
      step(d, s);
    }
  }
  for (int k = 0; k < 40; ++k) {  // let time run: retries, samples, link loss, announces
    s.now += 50;
    step(d, s);
  }
  return 0;
}
