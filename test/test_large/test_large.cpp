// Large values in fragments (docs/PROTOCOL.md 12) and Lists (PROTOCOL.md 6) on the device: a 1 KB
// struct written, read and streamed; reassembly and every way it is abandoned; capacity; the
// duplicate memory for a retried large control; fragments sized to what the hub accepts; Lists
// as variables, controls and action arguments, with every invalid case.
#include <gtest/gtest.h>

#include <numeric>

#include <nlohmann/json.hpp>

#include "fakes.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"
#include "hubwire/wire/bytes.h"

using namespace hubwire;
using namespace hubwire::test;

namespace {

struct Kilo {
  uint32_t words[200];
  float f[56];
} kilo;
static_assert(sizeof(Kilo) == 1024, "1 KB");
List<int16_t, 8> path;
List<uint8_t, 200> blob;  // 201 bytes on the wire when full
uint8_t small[4];
int kiloChanges, pathChanges, stepsCalls;
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
int pinsCalls;
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

const uint8_t kKilo = 1, kPath = 2, kBlob = 3, kSteps = 4, kSum = 5, kTrues = 6, kSmall = 7, kPins = 8, kRecent = 9;

Bytes operator+(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

Bytes bytesOf(const void* p, size_t n) { return Bytes((const uint8_t*)p, (const uint8_t*)p + n); }

// The F payloads carrying (type, payload) for a receiver taking max bytes a frame.
std::vector<Bytes> split(uint8_t type, const Bytes& payload, size_t max = HUBWIRE_MAX_PAYLOAD) {
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

class Large : public ::testing::Test {
 protected:
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  hubwire::Session device{port};

  void SetUp() override {
    memset(&kilo, 0, sizeof(kilo));
    path.clear();
    blob.clear();
    kiloChanges = pathChanges = stepsCalls = 0;
    ASSERT_TRUE(device.begin(large, 9));
  }

  void link(uint16_t hubMax = 255) {
    Bytes hello = hubHello(3);
    storeU16(&hello[6], hubMax);
    sendFrame(stream, '*', 0, 0, hello);
    device.update();
    ASSERT_TRUE(device.linked());
    device.update();
    drain(stream);
  }

  // Sends frames; returns what the device sent, heartbeats aside.
  std::vector<RxFrame> send(uint8_t seq, uint8_t id, const std::vector<Bytes>& fragments) {
    for (auto& f : fragments) sendFrame(stream, 'F', seq, id, f);
    return run();
  }
  std::vector<RxFrame> run() {
    while (!stream.in.empty()) device.update();
    std::vector<RxFrame> got;
    for (auto& f : drain(stream))
      if (f.type != 'H') got.push_back(f);
    return got;
  }
  uint16_t dropped() { return device.counters().dropped; }
};

// Reassembles the device's fragments of one message; checks they come offset 0 first, contiguous,
// each of the given data size but the last.
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

TEST_F(Large, DeclarationsSizeTheOneBuffer) {
  EXPECT_EQ((HubwireLarge<true, void>::capacity), 1024);  // kilo; blob and sum take 201
  EXPECT_NE((HubwireLarge<true, void>::state), nullptr);
  EXPECT_EQ(hubwire_channels_large::features & (kUsesLarge | kUsesLists), kUsesLarge | kUsesLists);
  auto json = nlohmann::json::parse(std::string(large.json, large.jsonLength));
  auto& ch = json["ch"];
  EXPECT_EQ(ch[kPath - 1]["t"], "i16");
  EXPECT_EQ(ch[kPath - 1]["vc"], 8);
  EXPECT_FALSE(ch[kPath - 1].contains("c"));
  EXPECT_EQ(ch[kSum - 1]["t"], "u16");
  EXPECT_EQ(ch[kSum - 1]["vc"], 100);
  EXPECT_EQ(ch[kSum - 1]["rt"], "u32");
  EXPECT_EQ(ch[kSmall - 1]["c"], 4);
  EXPECT_EQ(ch[kPins - 1]["rt"], "u8");
  EXPECT_EQ(ch[kPins - 1]["rvc"], 3);
  EXPECT_EQ(ch[kPins - 1]["t"], "u8");
  EXPECT_FALSE(ch[kPins - 1].contains("vc"));
  EXPECT_EQ(ch[kRecent - 1]["rt"], "i16");
  EXPECT_EQ(ch[kRecent - 1]["rvc"], 3);
  EXPECT_FALSE(ch[kKilo - 1].contains("rvc"));
}

TEST_F(Large, AKilobyteStructIsWrittenInFragmentsAndAppliedOnce) {
  link();
  Bytes value = pattern(1024, 1);
  auto fragments = split('C', value);
  ASSERT_EQ(fragments.size(), 38u);  // 1024 / 27
  auto got = send(0x40, kKilo, fragments);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  EXPECT_EQ(got[0].seq, 0x40);
  EXPECT_EQ(got[0].id, kKilo);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), value);
  EXPECT_EQ(kiloChanges, 1);
}

TEST_F(Large, ARetriedLargeControlIsAnsweredFromMemoryNotAppliedTwice) {
  link();
  Bytes first = pattern(1024, 2), other = pattern(1024, 3);
  auto got = send(0x41, kKilo, split('C', first));
  ASSERT_EQ(got.size(), 1u);
  // the retry (same seq) carries other bytes: were it applied, kilo would hold them
  got = send(0x41, kKilo, split('C', other));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  EXPECT_EQ(got[0].seq, 0x41);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), first);
  EXPECT_EQ(kiloChanges, 1);
  got = send(0x42, kKilo, split('C', other));  // a new seq is a new write
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), other);
  EXPECT_EQ(kiloChanges, 2);
}

TEST_F(Large, OutOfOrderRepeatedOrMissingFragmentsAbandonTheValue) {
  link();
  Bytes value = pattern(1024, 4);
  auto f = split('C', value);
  struct Case {
    const char* what;
    std::vector<Bytes> frames;
    int dropped;
  } cases[] = {
      {"swapped", {f[0], f[2], f[1]}, 2},
      {"repeated", {f[0], f[1], f[1], f[2]}, 2},
      {"missing last", std::vector<Bytes>(f.begin(), f.end() - 1), 0},
      {"missing first", std::vector<Bytes>(f.begin() + 1, f.end()), (int)f.size() - 1},
  };
  for (auto& c : cases) {
    SCOPED_TRACE(c.what);
    uint16_t before = dropped();
    auto got = send(0x50, kKilo, c.frames);
    EXPECT_TRUE(got.empty());
    EXPECT_EQ(dropped() - before, c.dropped);
    EXPECT_EQ(kiloChanges, 0);
    EXPECT_EQ(kilo.words[0], 0u);
  }
  // the hub's retry of the whole value goes through; the missing-last one was abandoned by it
  auto got = send(0x50, kKilo, f);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), value);
}

TEST_F(Large, AFragmentOfAnotherMessageAbandonsTheOneInProgress) {
  link();
  Bytes value = pattern(1024, 5);
  auto f = split('C', value);
  for (size_t i = 0; i < 5; ++i) sendFrame(stream, 'F', 0x51, kKilo, f[i]);
  sendFrame(stream, 'F', 0x52, kKilo, f[5]);  // same offset, other seq
  uint16_t before = dropped();
  for (size_t i = 6; i < f.size(); ++i) sendFrame(stream, 'F', 0x51, kKilo, f[i]);
  auto got = run();
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(dropped() - before, (int)f.size() - 5);
  EXPECT_EQ(kiloChanges, 0);
}

TEST_F(Large, OtherFramesBetweenFragmentsDoNotDisturbTheReassembly) {
  link();
  Bytes value = pattern(1024, 6);
  auto f = split('C', value);
  for (size_t i = 0; i < f.size(); ++i) {
    sendFrame(stream, 'F', 0x53, kKilo, f[i]);
    if (i == 10) sendFrame(stream, 'R', 0x54, kSmall);  // a read between two fragments
    if (i == 20) sendFrame(stream, 'H', 1, 0, Bytes(10, 0));
  }
  auto got = run();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].type, 'r');
  EXPECT_EQ(got[0].seq, 0x54);
  EXPECT_EQ(got[1].type, 0x07);
  EXPECT_EQ(got[1].seq, 0x53);
  EXPECT_EQ(bytesOf(&kilo, sizeof(kilo)), value);
}

TEST_F(Large, ATotalOverCapacityIsRefusedAtOnceAndTheRestDropped) {
  link();
  Bytes value = pattern(1025, 7);
  auto f = split('C', value);
  uint16_t before = dropped();
  auto got = send(0x55, kKilo, f);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x15);
  EXPECT_EQ(got[0].seq, 0x55);
  EXPECT_EQ(got[0].id, kKilo);
  EXPECT_EQ(got[0].payload, Bytes{kErrBadLength});
  EXPECT_EQ(dropped() - before, (int)f.size() - 1);
  EXPECT_EQ(kiloChanges, 0);
  // a message the device does not answer (an event) is only counted as overflow
  uint16_t overflow = device.counters().overflow;
  got = send(0x56, kKilo, split('!', pattern(1100, 8)));
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(device.counters().overflow - overflow, 1);
}

TEST_F(Large, AWellFormedLargeMessageThatIsNoControlGetsWhatALongOneWould) {
  link();
  auto got = send(0x57, kKilo, split('R', pattern(40, 9)));  // a read carries nothing
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x15);
  EXPECT_EQ(got[0].seq, 0x57);
  EXPECT_EQ(got[0].payload, Bytes{kErrBadLength});
  uint16_t before = dropped();
  got = send(0x58, kKilo, split('!', pattern(40, 9)));  // the hub's events fit a frame
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(dropped() - before, 1);
  before = dropped();
  got = send(0x59, kKilo, {Bytes{'C', 0, 0, 4, 0}});  // a fragment without data
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(dropped() - before, 1);
}

TEST_F(Large, ALargeReadIsAnsweredInFragmentsSizedForTheHub) {
  for (uint16_t hubMax : {255, 40, 16}) {
    SCOPED_TRACE(hubMax);
    stream.in.clear();
    device.~Session();
    new (&device) hubwire::Session(port);
    SetUp();
    link(hubMax);
    Bytes value = pattern(1024, 10);
    memcpy(&kilo, value.data(), 1024);
    sendFrame(stream, 'R', 0x60, kKilo);
    auto got = run();
    size_t per = std::min<size_t>(hubMax, HUBWIRE_MAX_PAYLOAD) - kFragmentHeader;
    EXPECT_EQ(got.size(), (1024 + per - 1) / per);
    for (auto& f : got) EXPECT_LE(f.payload.size(), std::min<size_t>(hubMax, HUBWIRE_MAX_PAYLOAD));
    EXPECT_EQ(reassemble(got, 'r', 0x60, kKilo, per), value);
  }
}

TEST_F(Large, ALargeValueIsStreamedAsFragmentedSamples) {
  link();
  Bytes value = pattern(1024, 11);
  memcpy(&kilo, value.data(), 1024);
  sendFrame(stream, 'S', 0x61, kKilo, le<uint16_t>(100));
  auto got = run();
  ASSERT_GE(got.size(), 2u);
  EXPECT_EQ(got[0].type, 0x07);
  got.erase(got.begin());
  Bytes sample = reassemble(got, 'D', 0, kKilo, HUBWIRE_MAX_PAYLOAD - kFragmentHeader);
  ASSERT_EQ(sample.size(), 2u + 1024);
  EXPECT_EQ(loadU16(&sample[0]), 0);
  EXPECT_EQ(Bytes(sample.begin() + 2, sample.end()), value);
  // the next sample, interval ms later, with the next sample seq and the time since
  clock.now += 100;
  kilo.words[0] = 0xDEADBEEF;
  device.update();
  got.clear();
  for (auto& f : drain(stream))
    if (f.type != 'H') got.push_back(f);
  sample = reassemble(got, 'D', 1, kKilo, HUBWIRE_MAX_PAYLOAD - kFragmentHeader);
  ASSERT_EQ(sample.size(), 2u + 1024);
  EXPECT_EQ(loadU16(&sample[0]), 100);
  EXPECT_EQ(loadU32(&sample[2]), 0xDEADBEEFu);
}

TEST_F(Large, AListThatIsNotFullGoesInOneFrame) {
  link();
  blob.clear();
  for (uint8_t i = 0; i < 10; ++i) blob.push(i);
  sendFrame(stream, 'R', 0x62, kBlob);
  auto got = run();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 'r');
  EXPECT_EQ(got[0].payload, (Bytes{10, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  for (uint8_t i = 10; i < 200; ++i) blob.push(i);  // full: 201 bytes
  sendFrame(stream, 'R', 0x63, kBlob);
  got = run();
  Bytes whole = reassemble(got, 'r', 0x63, kBlob, HUBWIRE_MAX_PAYLOAD - kFragmentHeader);
  ASSERT_EQ(whole.size(), 201u);
  EXPECT_EQ(whole[0], 200);
  for (uint8_t i = 0; i < 200; ++i) EXPECT_EQ(whole[1 + i], i);
}

TEST_F(Large, ALargeListIsWrittenAndPassedToAnAction) {
  link();
  Bytes list{150};
  for (uint8_t i = 0; i < 150; ++i) list.push_back(i);
  auto got = send(0x64, kBlob, split('C', list));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 0x07);
  ASSERT_EQ(blob.size(), 150);
  EXPECT_EQ(blob[149], 149);
  Bytes arg{100};
  uint32_t want = 0;
  for (uint16_t i = 0; i < 100; ++i) {
    Bytes e = le<uint16_t>((uint16_t)(i * 600));
    arg.insert(arg.end(), e.begin(), e.end());
    want += i * 600u;
  }
  got = send(0x65, kSum, split('C', arg));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 'r');
  EXPECT_EQ(got[0].seq, 0x65);
  EXPECT_EQ(got[0].payload, le<uint32_t>(want));
}

// ---- Lists in one frame: the session's checks, in the order PROTOCOL.md 6 gives ----

class Lists : public Large {
 protected:
  RxFrame control(uint8_t id, const Bytes& payload) {
    static uint8_t seq = 0;
    sendFrame(stream, 'C', ++seq, id, payload);
    auto got = run();
    EXPECT_EQ(got.size(), 1u);
    return got.empty() ? RxFrame{0, 0, 0, {}} : got[0];
  }
  static Bytes nak(ErrorCode c) { return Bytes{(uint8_t)c}; }
};

Bytes i16s(std::initializer_list<int16_t> v) {
  Bytes b{(uint8_t)v.size()};
  for (int16_t x : v) {
    Bytes e = le(x);
    b.insert(b.end(), e.begin(), e.end());
  }
  return b;
}

TEST_F(Lists, WrittenReadAndCheckedElementByElement) {
  link();
  EXPECT_EQ(control(kPath, i16s({1, -2, 100})).type, 0x07);
  ASSERT_EQ(path.size(), 3);
  EXPECT_EQ(path[1], -2);
  EXPECT_EQ(pathChanges, 1);
  sendFrame(stream, 'R', 0x70, kPath);
  auto got = run();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].payload, i16s({1, -2, 100}));
  struct Bad {
    const char* what;
    Bytes payload;
    ErrorCode code;
  } bad[] = {
      {"count over capacity", i16s({1, 2, 3, 4, 5, 6, 7, 8, 9}), kErrBadValue},
      {"count over capacity, payload short", Bytes{9, 1, 0}, kErrBadValue},
      {"no count byte", Bytes{}, kErrBadLength},
      {"half an element", Bytes{1, 5}, kErrBadLength},
      {"count 1, two elements", Bytes{1, 5, 0, 6, 0}, kErrBadLength},
      {"first element out of range", i16s({101, 0}), kErrOutOfRange},
      {"last element out of range", i16s({0, 5, -101}), kErrOutOfRange},
  };
  for (auto& b : bad) {
    SCOPED_TRACE(b.what);
    RxFrame f = control(kPath, b.payload);
    EXPECT_EQ(f.type, 0x15);
    EXPECT_EQ(f.payload, nak(b.code));
    EXPECT_EQ(path.size(), 3);  // nothing stored
    EXPECT_EQ(pathChanges, 1);
  }
  EXPECT_EQ(control(kPath, Bytes{0}).type, 0x07);  // empty
  EXPECT_EQ(path.size(), 0);
}

TEST_F(Lists, AControlTakesAListAndMayRefuseIt) {
  link();
  EXPECT_EQ(control(kSteps, i16s({7, -7})).type, 0x07);
  EXPECT_EQ(stepsCalls, 1);
  ASSERT_EQ(lastSteps.size(), 2);
  EXPECT_EQ(lastSteps[1], -7);
  RxFrame f = control(kSteps, i16s({1, 2, 3}));
  EXPECT_EQ(f.payload, nak(kErrRejected));
  EXPECT_EQ(stepsCalls, 2);
  f = control(kSteps, i16s({1, 2, 3, 4, 5}));
  EXPECT_EQ(f.payload, nak(kErrBadValue));
  EXPECT_EQ(stepsCalls, 2);  // not called
}

TEST_F(Lists, BoolElementsAreZeroOrOne) {
  link();
  RxFrame f = control(kTrues, Bytes{3, 1, 0, 1});
  EXPECT_EQ(f.type, 'r');
  EXPECT_EQ(f.payload, Bytes{2});
  f = control(kTrues, Bytes{3, 1, 2, 1});
  EXPECT_EQ(f.type, 0x15);
  EXPECT_EQ(f.payload, nak(kErrBadValue));
}

TEST_F(Lists, AnActionReturnsAListWithItsCountAndARetryIsAnsweredFromMemory) {
  link();
  pinsCalls = 0;
  sendFrame(stream, 'C', 0x71, kPins, Bytes{5});
  auto got = run();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, 'r');
  EXPECT_EQ(got[0].payload, (Bytes{3, 5, 6, 7}));
  sendFrame(stream, 'C', 0x71, kPins, Bytes{5});  // the hub's retry: same seq
  got = run();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].payload, (Bytes{3, 5, 6, 7}));
  EXPECT_EQ(pinsCalls, 1);
  EXPECT_EQ(control(kPins, Bytes{0}).payload, Bytes{0});  // an empty list
  EXPECT_EQ(control(kPins, Bytes{2}).payload, (Bytes{2, 2, 3}));
  EXPECT_EQ(control(kRecent, Bytes{}).payload, (Bytes{2}) + le<int16_t>(-300) + le<int16_t>(7));
}

TEST(ListCodec, MemoryAndWireForms) {
  ValueType t{listOf(kU32), 5, nullptr};
  EXPECT_EQ(t.wireSize(), 21);
  EXPECT_EQ(t.memSize(), sizeof(List<uint32_t, 5>));
  List<uint32_t, 5> l{};
  l.push(7);
  l.push(0x01020304);
  Bytes wire(t.wireSize());
  wire.resize(t.toWire(&l, wire.data()));
  EXPECT_EQ(wire, (Bytes{2, 7, 0, 0, 0, 4, 3, 2, 1}));
  EXPECT_EQ(t.wireLength(&l), 9);
  List<uint32_t, 5> back{};
  back.count = 4;
  t.fromWire(wire.data(), (uint16_t)wire.size(), &back);
  EXPECT_EQ(back.size(), 2);
  EXPECT_EQ(back[1], 0x01020304u);
  l.count = 200;  // a sketch that overfilled count sends the capacity
  wire.assign(t.wireSize(), 0);
  EXPECT_EQ(t.toWire(&l, wire.data()), 21);
  EXPECT_EQ(wire[0], 5);
  EXPECT_TRUE(l.push(1) == false);
  l.clear();
  EXPECT_EQ(l.size(), 0);
  EXPECT_EQ(l.capacity(), 5);
}

TEST(ListCodec, ChecksInOrder) {
  ValueType t{listOf(kI16), 3, nullptr};
  uint8_t w[16] = {0};
  EXPECT_EQ(t.check(w, 0), kErrBadLength);
  w[0] = 4;
  EXPECT_EQ(t.check(w, 1), kErrBadValue);  // the count first, whatever the length
  EXPECT_EQ(t.check(w, 9), kErrBadValue);
  w[0] = 2;
  EXPECT_EQ(t.check(w, 4), kErrBadLength);
  EXPECT_EQ(t.check(w, 6), kErrBadLength);
  EXPECT_EQ(t.check(w, 5), kOk);
  ValueType b{listOf(kBool), 3, nullptr};
  uint8_t bw[] = {3, 1, 0, 2};
  EXPECT_EQ(b.check(bw, 4), kErrBadValue);
  bw[3] = 1;
  EXPECT_EQ(b.check(bw, 4), kOk);
}

// Any window of a value's wire form, taken from memory, is the same bytes as the whole wire form.
TEST(WireRange, EveryWindowMatchesTheWholeValue) {
  struct Padded {
    uint8_t a;
    uint32_t b;
    uint16_t c[3];
    bool d;
  } p = {0xA1, 0xB2B3B4B5, {0xC1C2, 0xC3C4, 0xC5C6}, true};
  // "a:u8,b:u32,c:u16[3],d:bool" compiled (channels/layout.h)
  static const char layout[] = {kU8, 1, kU32, 1, kU16, 3, kBool, 1, kVoid};
  ValueType s{kStruct, 0, layout};
  List<uint16_t, 6> l{};
  for (uint16_t i = 0; i < 4; ++i) l.push((uint16_t)(0x1111 * (i + 1)));
  ValueType lt{listOf(kU16), 6, nullptr};
  char str[9] = "window";
  ValueType st{kStr, 8, nullptr};
  int16_t arr[4] = {1, -1, 300, -300};
  ValueType at{kI16, 4, nullptr};
  struct Case {
    const ValueType* t;
    const void* mem;
  } cases[] = {{&s, &p}, {&lt, &l}, {&st, str}, {&at, arr}};
  for (auto& c : cases) {
    Bytes whole(c.t->wireSize() + 1);
    whole.resize(c.t->toWire(c.mem, whole.data()));
    ASSERT_EQ(whole.size(), c.t->wireLength(c.mem));
    for (uint16_t off = 0; off < whole.size(); ++off)
      for (uint16_t n = 1; off + n <= whole.size(); ++n) {
        Bytes part(n, 0xEE);
        c.t->wireRange(c.mem, off, part.data(), n);
        ASSERT_EQ(part, Bytes(whole.begin() + off, whole.begin() + off + n)) << off << "+" << n;
      }
  }
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
