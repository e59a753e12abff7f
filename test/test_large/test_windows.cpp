// Reading a large value in windows (docs/PROTOCOL.md 12.8): R [u16 offset, u16 count] answered by
// one r [u16 offset, u16 total, u32 FNV-1a of the whole value, bytes], sized for the hub's frame.
#include "large_sketch.h"

using namespace large_sketch;

namespace {

uint32_t fnv(const Bytes& b) {
  uint32_t h = kFnvOffset;
  for (uint8_t c : b) h = fnv1a(h, c);
  return h;
}

Bytes window(uint16_t offset, uint16_t count) {
  Bytes p(4);
  storeU16(&p[0], offset);
  storeU16(&p[2], count);
  return p;
}

class Windows : public Large {
 protected:
  RxFrame ask(uint8_t seq, uint8_t id, const Bytes& payload) {
    sendFrame(stream, 'R', seq, id, payload);
    auto got = run();
    EXPECT_EQ(got.size(), 1u);  // one frame, never fragments
    if (got.empty()) return RxFrame{0, 0, 0, {}};
    EXPECT_EQ(got[0].seq, seq);
    EXPECT_EQ(got[0].id, id);
    return got[0];
  }
};

TEST_F(Windows, AWindowCarriesItsBytesTheTotalAndTheWholeValuesHash) {
  link();
  Bytes value = fillKilo(20);
  const size_t room = HUBWIRE_MAX_PAYLOAD - kWindowHeader;
  struct Case {
    uint16_t offset, count;
    size_t n;
  } cases[] = {
      {0, 10, 10}, {0, 1000, room}, {500, 0xFFFF, room}, {1020, 100, 4}, {1024, 10, 0}, {7, 1, 1},
  };
  for (auto& c : cases) {
    SCOPED_TRACE(c.offset);
    RxFrame f = ask(0x70, kKilo, window(c.offset, c.count));
    ASSERT_EQ(f.type, 'r');
    ASSERT_EQ(f.payload.size(), kWindowHeader + c.n);
    EXPECT_EQ(loadU16(&f.payload[0]), c.offset);
    EXPECT_EQ(loadU16(&f.payload[2]), 1024);
    EXPECT_EQ(loadU32(&f.payload[4]), fnv(value));
    EXPECT_EQ(Bytes(f.payload.begin() + kWindowHeader, f.payload.end()),
              Bytes(value.begin() + c.offset, value.begin() + c.offset + c.n));
  }
}

TEST_F(Windows, AWindowFitsWhatTheHubAccepts) {
  for (uint16_t hubMax : {255, 40, 16}) {
    SCOPED_TRACE(hubMax);
    relink(hubMax);
    Bytes value = fillKilo(21);
    RxFrame f = ask(0x71, kKilo, window(100, 1000));
    size_t n = std::min<size_t>(hubMax, HUBWIRE_MAX_PAYLOAD) - kWindowHeader;
    ASSERT_EQ(f.payload.size(), kWindowHeader + n);
    EXPECT_EQ(Bytes(f.payload.begin() + kWindowHeader, f.payload.end()),
              Bytes(value.begin() + 100, value.begin() + 100 + n));
  }
}

TEST_F(Windows, TheHashFollowsTheValueAndAssembledWindowsMatchIt) {
  link();
  Bytes value = fillKilo(22), assembled;
  uint32_t first = 0;
  for (uint16_t at = 0; at < 1024;) {
    RxFrame f = ask(0x72, kKilo, window(at, 0xFFFF));
    ASSERT_GT(f.payload.size(), kWindowHeader);
    first = loadU32(&f.payload[4]);
    assembled.insert(assembled.end(), f.payload.begin() + kWindowHeader, f.payload.end());
    at = (uint16_t)(at + f.payload.size() - kWindowHeader);
  }
  EXPECT_EQ(assembled, value);
  EXPECT_EQ(fnv(assembled), first);
  kilo.words[255 % 200] ^= 1;  // the value changes: every window says so
  RxFrame f = ask(0x73, kKilo, window(0, 4));
  EXPECT_NE(loadU32(&f.payload[4]), first);
  EXPECT_EQ(loadU32(&f.payload[4]), fnv(bytesOf(&kilo, sizeof(kilo))));
}

TEST_F(Windows, AListsWindowIsOfItsWireFormAndItsCurrentLength) {
  link();
  blob.clear();
  for (uint8_t i = 0; i < 50; ++i) blob.push(i);
  RxFrame f = ask(0x74, kBlob, window(0, 10));
  ASSERT_EQ(f.payload.size(), kWindowHeader + 10u);
  EXPECT_EQ(loadU16(&f.payload[2]), 51);  // count byte, then 50 elements
  Bytes wire{50};
  for (uint8_t i = 0; i < 50; ++i) wire.push_back(i);
  EXPECT_EQ(loadU32(&f.payload[4]), fnv(wire));
  EXPECT_EQ(Bytes(f.payload.begin() + kWindowHeader, f.payload.end()), Bytes(wire.begin(), wire.begin() + 10));
  f = ask(0x75, kBlob, window(45, 10));
  EXPECT_EQ(Bytes(f.payload.begin() + kWindowHeader, f.payload.end()), Bytes(wire.begin() + 45, wire.end()));
}

TEST_F(Windows, PastTheEndIsBadOffsetAndOtherLengthsStayBadLength) {
  link();
  RxFrame f = ask(0x76, kKilo, window(1025, 4));
  EXPECT_EQ(f.type, kMsgNak);
  EXPECT_EQ(f.payload, Bytes{kErrBadOffset});
  for (size_t len : {1u, 2u, 3u, 5u}) {
    SCOPED_TRACE(len);
    f = ask(0x77, kKilo, Bytes(len));
    EXPECT_EQ(f.type, kMsgNak);
    EXPECT_EQ(f.payload, Bytes{kErrBadLength});
  }
}

}  // namespace
