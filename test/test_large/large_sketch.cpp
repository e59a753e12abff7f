// The sketch of the large-value and List suites (large_sketch.h).
#include "large_sketch.h"

namespace large_sketch {

Kilo kilo;
static_assert(sizeof(Kilo) == 1024, "1 KB");
List<int16_t, 8> path;
List<uint8_t, 200> blob;  // 201 bytes on the wire when full
uint8_t small[4];
int kiloChanges, pathChanges, stepsCalls, pinsCalls;
List<int16_t, 4> lastSteps;

void kiloChanged() { ++kiloChanges; }
void pathChanged() { ++pathChanges; }
bool setSteps(const List<int16_t, 4>& s) {
  ++stepsCalls;
  lastSteps = s;
  return s.size() != 3;  // refuses three steps
}
uint32_t sum(const List<uint16_t, 100>& v) {
  uint32_t s = 0;
  for (uint8_t i = 0; i < v.size(); ++i) s += v[i];
  return s;
}
List<uint8_t, 3> pins(uint8_t bank) {  // bank 0: none; else bank, bank + 1, ... up to 3
  ++pinsCalls;
  List<uint8_t, 3> l{};
  for (uint8_t i = 0; i < bank && i < 3; ++i) l.push((uint8_t)(bank + i));
  return l;
}
List<int16_t, 3> recent() {
  List<int16_t, 3> l{};
  l.push(-300);
  l.push(7);
  return l;
}
uint8_t trues(const List<bool, 4>& v) {
  uint8_t n = 0;
  for (uint8_t i = 0; i < v.size(); ++i) n += v[i];
  return n;
}

}  // namespace large_sketch

// At file scope, as in a sketch: the macro specialises templates of the global namespace.
using namespace large_sketch;
HUBWIRE_CHANNELS(large, "large",
  expose("kilo", kilo, "words:u32[200],f:f32[56]").writable().streamable().onChange(kiloChanged),  // 1
  expose("path", path).writable().range(-100, 100).onChange(pathChanged),                            // 2
  expose("blob", blob).writable().streamable(),                                                      // 3
  control("steps", setSteps),                                                                        // 4
  action("sum", sum),                                                                                // 5
  action("trues", trues),                                                                            // 6
  expose("small", small).writable(),                                                                 // 7
  action("pins", pins),                                                                              // 8
  action("recent", recent));                                                                         // 9

namespace large_sketch {

const ChannelTable& table() { return large; }
uint16_t features() { return hubwire_channels_large::features; }

Bytes operator+(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

Bytes bytesOf(const void* p, size_t n) { return Bytes((const uint8_t*)p, (const uint8_t*)p + n); }

std::vector<Bytes> split(uint8_t type, const Bytes& payload, size_t max) {
  std::vector<Bytes> out;
  size_t per = max - kFragmentHeader;
  for (size_t off = 0; off < payload.size(); off += per) {
    Bytes f(5);
    f[0] = type;
    storeU16(&f[1], (uint16_t)off);
    storeU16(&f[3], (uint16_t)payload.size());
    size_t n = std::min(per, payload.size() - off);
    f.insert(f.end(), payload.begin() + off, payload.begin() + off + n);
    out.push_back(f);
  }
  return out;
}

Bytes pattern(size_t n, uint8_t salt) {
  Bytes b(n);
  for (size_t i = 0; i < n; ++i) b[i] = (uint8_t)(i * 31 + salt + (i >> 8));
  return b;
}

Bytes reassemble(const std::vector<RxFrame>& frames, uint8_t type, uint8_t seq, uint8_t id, size_t per) {
  Bytes whole;
  for (size_t i = 0; i < frames.size(); ++i) {
    const RxFrame& f = frames[i];
    EXPECT_EQ(f.type, 'F');
    EXPECT_EQ(f.seq, seq);
    EXPECT_EQ(f.id, id);
    EXPECT_EQ(f.payload[0], type);
    EXPECT_EQ(loadU16(&f.payload[1]), whole.size());
    size_t n = f.payload.size() - kFragmentHeader;
    if (i + 1 < frames.size()) {
      EXPECT_EQ(n, per) << "fragment " << i;
    }
    whole.insert(whole.end(), f.payload.begin() + kFragmentHeader, f.payload.end());
    EXPECT_EQ(loadU16(&f.payload[3]), i + 1 < frames.size() ? loadU16(&frames[0].payload[3]) : whole.size());
  }
  return whole;
}

}  // namespace large_sketch
