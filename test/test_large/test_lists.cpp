// Lists (docs/PROTOCOL.md 6) on the device: written, read and checked in the order the protocol
// gives, as a control's and an action's argument and an action's result; the codec's memory and
// wire forms; any window of a value's wire form read from memory (what fragments send).
#include "large_sketch.h"

using namespace large_sketch;

namespace {

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
