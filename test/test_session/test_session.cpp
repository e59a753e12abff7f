// The device session against a fake stream and a fake clock: every message kind, every NAK,
// retries, duplicate suppression, link loss and failsafe, stream timing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <new>
#include <random>
#include <type_traits>

#include <nlohmann/json.hpp>

#include "fakes.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"
#include "hubwire/wire/bytes.h"

using namespace hubwire;
using namespace hubwire::test;

namespace {

// The sketch under test: globals, because channels are declared at file scope, as in a sketch.
float speed;
int16_t counts[3];
char label[9] = "hi";
struct Pose {
  float x;
  uint8_t ok;
  int16_t t[2];
} pose;
bool lamp;
int16_t temps[2];
Event<uint16_t> alarm;
int ledCalls, pingCalls, lostCalls, upCalls, changes;
uint8_t lastLed;

void setLed(uint8_t v) {
  lastLed = v;
  ++ledCalls;
}
bool refuseOdd(uint16_t v) { return v % 2 == 0; }
int32_t ping(int16_t v) {
  ++pingCalls;
  return v * 2;
}
void reset() { ++pingCalls; }
void changed() { ++changes; }
void lost() { ++lostCalls; }
void up() { ++upCalls; }

HUBWIRE_CHANNELS(tester, device("tester").firmware("2.1"),
  expose("speed", speed).writable().streamable().range(-1, 1).unit("m/s").failsafe(0).onChange(changed),  // 1
  expose("counts", counts).streamable(),                                                                 // 2
  expose("label", label).writable().describe("a \"quoted\" label"),                                      // 3
  expose("pose", pose, "x:f32,ok:u8,t:i16[2]").writable(),                                              // 4
  control("led", setLed),                                                                                // 5
  control("even", refuseOdd),                                                                            // 6
  action("ping", ping),                                                                                  // 7
  action("reset", reset),                                                                                // 8
  event("alarm", alarm),                                                                                 // 9
  expose("lamp", lamp).writable().failsafe(1),                                                           // 10
  expose("temps", temps).writable().range(-40, 125).failsafe(-40));                                       // 11

const uint8_t kSpeed = 1, kCounts = 2, kLabel = 3, kPose = 4, kLed = 5, kEven = 6, kPing = 7, kReset = 8, kAlarm = 9,
              kLamp = 10, kTemps = 11;

Bytes operator+(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

uint32_t fnv(const std::string& s) {
  uint32_t h = kFnvOffset;
  for (unsigned char c : s) h = fnv1a(h, c);
  return h;
}

class Session : public ::testing::Test {
 protected:
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  hubwire::Session device{port};
  uint8_t seq = 0;
  std::vector<RxFrame> others;  // frames sent in the same update() as the last answer
  std::vector<RxFrame> linkFrames;

  void SetUp() override {
    speed = 0;
    lamp = false;
    temps[0] = temps[1] = 0;
    memset(counts, 0, sizeof(counts));
    strcpy(label, "hi");
    ledCalls = pingCalls = lostCalls = upCalls = changes = 0;
    device.onLinkLost(lost);
    device.onLinkUp(up);
    ASSERT_TRUE(device.begin(tester, 0xABCDEF01));
  }

  std::vector<RxFrame> pump(uint32_t advanceMs = 0) {
    clock.now += advanceMs;
    device.update();
    return drain(stream);
  }

  void link(uint32_t nonce = 77) {
    drain(stream);
    sendFrame(stream, '*', 0, 0, hubHello(nonce));
    linkFrames = pump();
    ASSERT_TRUE(device.linked());
    ASSERT_FALSE(linkFrames.empty());
    EXPECT_EQ(linkFrames[0].type, '*');
  }

  // Sends a transaction with a fresh seq and returns the answer (the first frame echoing it).
  RxFrame transact(uint8_t type, uint8_t id, const Bytes& payload = Bytes(), int useSeq = -1) {
    uint8_t s = useSeq >= 0 ? (uint8_t)useSeq : ++seq;
    sendFrame(stream, type, s, id, payload);
    others.clear();
    RxFrame answer{0, 0, 0, {}};
    bool found = false;
    for (auto& f : pump()) {
      if (!found && f.seq == s && f.id == id && f.type != 'H' && f.type != '!' && f.type != 'D') {
        answer = f;
        found = true;
      } else {
        others.push_back(f);
      }
    }
    if (found) return answer;
    ADD_FAILURE() << "no answer to " << type;
    return RxFrame{0, 0, 0, {}};
  }

  void expectNak(const RxFrame& f, uint8_t code) {
    EXPECT_EQ(f.type, kMsgNak);
    ASSERT_EQ(f.payload.size(), 1u);
    EXPECT_EQ(f.payload[0], code);
  }

  std::string descriptor() {
    std::string out;
    for (;;) {
      Bytes req(3);
      storeU16(&req[0], (uint16_t)out.size());
      req[2] = 255;
      RxFrame f = transact('J', 0, req);
      EXPECT_EQ(f.type, 'J');
      EXPECT_EQ(loadU16(&f.payload[0]), out.size());
      uint16_t total = loadU16(&f.payload[2]);
      out.append(f.payload.begin() + 4, f.payload.end());
      if (out.size() >= total || f.payload.size() == 4) return out;
    }
  }
};

TEST_F(Session, AnnouncesItselfASecondAfterBootWithHashAndLength) {
  EXPECT_TRUE(drain(stream).empty());  // no nonce yet: it is drawn when the hub is first heard
  auto f = pump(HUBWIRE_ANNOUNCE_MS);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].type, '*');
  ASSERT_EQ(f[0].payload.size(), 16u);
  EXPECT_EQ(f[0].payload[0], 1);
  EXPECT_EQ(f[0].payload[1] & (kHelloDevice | kHelloReply), kHelloDevice);
  EXPECT_EQ(loadU32(&f[0].payload[2]), device.nonce());
  EXPECT_NE(device.nonce(), 0u);
  EXPECT_EQ(loadU16(&f[0].payload[6]), HUBWIRE_MAX_PAYLOAD);
  EXPECT_EQ(loadU16(&f[0].payload[8]), HUBWIRE_HEARTBEAT_MS);
  EXPECT_EQ(loadU32(&f[0].payload[10]), device.descriptorHash());
  EXPECT_EQ(loadU16(&f[0].payload[14]), device.descriptorLength());
  EXPECT_FALSE(device.linked());
}

TEST_F(Session, RepeatsAnnouncementWhileUnlinked) {
  pump(HUBWIRE_ANNOUNCE_MS);
  EXPECT_TRUE(pump(HUBWIRE_ANNOUNCE_MS - 1).empty());
  auto f = pump(1);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].type, '*');
}

// One boot of a sketch (the test sketch unless told) with the same seed every time, as a board that
// cannot tell boots apart.
struct Boot {
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  hubwire::Session device{port};
  bool begun;
  explicit Boot(const ChannelTable& sketch = tester) { begun = device.begin(sketch, 0x1234); }
  // Handshakes with a hub that accepts payloads of up to hubMax bytes; true when linked.
  bool link(uint16_t hubMax = 255) {
    Bytes hello = hubHello(5);
    storeU16(&hello[6], hubMax);
    sendFrame(stream, '*', 0, 0, hello);
    device.update();
    return device.linked();
  }
};

// A board that loses power boots with the same RAM, counter and code path every time; only the
// moment it first hears the hub differs. The nonce must differ with it, or the hub would take the
// new boot for the old session (and drop its first event as a duplicate).
TEST(Nonce, DependsOnWhenTheHubIsFirstHeard) {
  uint32_t seen[2];
  for (int boot = 0; boot < 2; ++boot) {
    Boot b;  // same seed each boot
    ASSERT_TRUE(b.begun);
    FakeStream& s = b.stream;
    FakeClock& c = b.clock;
    hubwire::Session& d = b.device;
    c.now += 40;
    c.us = 40000 + (uint32_t)boot * 1372;  // the hub's hello lands at another instant
    sendFrame(s, '*', 0, 0, hubHello(9));
    d.update();
    auto f = drain(s);
    ASSERT_FALSE(f.empty());
    seen[boot] = loadU32(&f[0].payload[2]);
    EXPECT_EQ(seen[boot], d.nonce());
  }
  EXPECT_NE(seen[0], seen[1]);
}

// In a simulator even the timing repeats (bytes that arrived during boot are read at a fixed
// instant); the hub's own random nonce, from the first hello heard, still differs per connection.
TEST(Nonce, DependsOnTheHubsNonceInTheFirstHelloHeard) {
  uint32_t seen[2];
  for (int boot = 0; boot < 2; ++boot) {
    Boot b;
    ASSERT_TRUE(b.begun);
    FakeStream& s = b.stream;
    FakeClock& c = b.clock;
    hubwire::Session& d = b.device;
    c.us = 40000;  // identical timing
    sendFrame(s, '*', 0, 0, hubHello(100 + (uint32_t)boot));
    d.update();
    seen[boot] = d.nonce();
    sendFrame(s, '*', 0, 0, hubHello(555));  // a later hub session does not change it
    d.update();
    EXPECT_EQ(d.nonce(), seen[boot]);
  }
  EXPECT_NE(seen[0], seen[1]);
}

TEST_F(Session, HandshakeAnswersHelloAndLinks) {
  link();
  EXPECT_EQ(upCalls, 1);
  sendFrame(stream, '*', 0, 0, hubHello(77, kHelloReply));  // a reply hello is not answered
  for (auto& f : pump()) EXPECT_NE(f.type, '*');
}

TEST_F(Session, RefusesOtherProtocolVersionsButStillSaysWhoItIs) {
  drain(stream);
  sendFrame(stream, '*', 0, 0, hubHello(5, 0, 2));
  auto f = pump();
  ASSERT_FALSE(f.empty());
  EXPECT_EQ(f[0].type, '*');
  EXPECT_FALSE(device.linked());
}

TEST_F(Session, ShortHelloIsNakedBadLength) {
  drain(stream);
  sendFrame(stream, '*', 0, 0, Bytes(15, 1));
  auto f = pump();
  ASSERT_EQ(f.size(), 1u);
  expectNak(f[0], kErrBadLength);
  EXPECT_FALSE(device.linked());
}

TEST_F(Session, DescriptorIsValidJsonMatchingHashAndDeclarations) {
  link();
  std::string d = descriptor();
  EXPECT_EQ(d.size(), device.descriptorLength());
  EXPECT_EQ(fnv(d), device.descriptorHash());
  auto j = nlohmann::json::parse(d);
  EXPECT_EQ(j["p"], 1);
  EXPECT_EQ(j["n"], "tester");
  EXPECT_EQ(j["fw"], "2.1");
  ASSERT_EQ(j["ch"].size(), 11u);
  auto s = j["ch"][0];
  EXPECT_EQ(s["id"], 1);
  EXPECT_EQ(s["n"], "speed");
  EXPECT_EQ(s["a"], "rws");
  EXPECT_EQ(s["t"], "f32");
  EXPECT_EQ(s["u"], "m/s");
  EXPECT_EQ(s["min"], -1);
  EXPECT_EQ(s["max"], 1);
  EXPECT_EQ(s["fs"], 0);
  EXPECT_EQ(j["ch"][1]["t"], "i16");
  EXPECT_EQ(j["ch"][1]["c"], 3);
  EXPECT_EQ(j["ch"][2]["t"], "str");
  EXPECT_EQ(j["ch"][2]["c"], 8);
  EXPECT_EQ(j["ch"][2]["d"], "a \"quoted\" label");
  auto p = j["ch"][3];
  EXPECT_EQ(p["t"], "struct");
  EXPECT_EQ(p["f"], nlohmann::json::parse(R"([{"n":"x","t":"f32"},{"n":"ok","t":"u8"},{"n":"t","t":"i16","c":2}])"));
  EXPECT_EQ(j["ch"][4]["a"], "w");
  EXPECT_EQ(j["ch"][4]["t"], "u8");
  EXPECT_EQ(j["ch"][6]["a"], "c");
  EXPECT_EQ(j["ch"][6]["t"], "i16");
  EXPECT_EQ(j["ch"][6]["rt"], "i32");
  EXPECT_EQ(j["ch"][7]["t"], "void");
  EXPECT_FALSE(j["ch"][7].contains("rt"));
  EXPECT_EQ(j["ch"][8]["a"], "e");
  EXPECT_EQ(j["ch"][8]["t"], "u16");
  // Integer ranges and failsafes print as integers of the channel's own type.
  auto t = j["ch"][10];
  EXPECT_EQ(t["t"], "i16");
  EXPECT_EQ(t["min"], -40);
  EXPECT_EQ(t["max"], 125);
  EXPECT_EQ(t["fs"], -40);
  EXPECT_EQ(d.find("\"min\":-40,\"max\":125,\"fs\":-40"), d.find("\"min\":-40"));
  // Byte for byte what main's run-time writer sent for the same declarations.
  EXPECT_EQ(d, R"({"p":1,"n":"tester","fw":"2.1","ch":[)"
               R"({"id":1,"n":"speed","a":"rws","t":"f32","u":"m/s","min":-1,"max":1,"fs":0},)"
               R"({"id":2,"n":"counts","a":"rs","t":"i16","c":3},)"
               R"({"id":3,"n":"label","a":"rw","t":"str","c":8,"d":"a \"quoted\" label"},)"
               R"({"id":4,"n":"pose","a":"rw","t":"struct","f":[{"n":"x","t":"f32"},{"n":"ok","t":"u8"},{"n":"t","t":"i16","c":2}]},)"
               R"({"id":5,"n":"led","a":"w","t":"u8"},{"id":6,"n":"even","a":"w","t":"u16"},)"
               R"({"id":7,"n":"ping","a":"c","t":"i16","rt":"i32"},{"id":8,"n":"reset","a":"c","t":"void"},)"
               R"({"id":9,"n":"alarm","a":"e","t":"u16"},{"id":10,"n":"lamp","a":"rw","t":"bool","fs":1},)"
               R"({"id":11,"n":"temps","a":"rw","t":"i16","c":2,"min":-40,"max":125,"fs":-40}]})");
}

// Ranges compare in the channel's own type: every element of an array is checked, the edges
// are inside, and a refused write changes nothing.
TEST_F(Session, IntegerRangesCheckEveryElementAtTheEdges) {
  link();
  temps[0] = temps[1] = 7;
  expectNak(transact('C', kTemps, le<int16_t>(0) + le<int16_t>(126)), kErrOutOfRange);
  expectNak(transact('C', kTemps, le<int16_t>(-41) + le<int16_t>(0)), kErrOutOfRange);
  expectNak(transact('C', kTemps, le<int16_t>(-32768) + le<int16_t>(0)), kErrOutOfRange);
  EXPECT_EQ(temps[0], 7);
  EXPECT_EQ(temps[1], 7);
  EXPECT_EQ(transact('C', kTemps, le<int16_t>(-40) + le<int16_t>(125)).type, kMsgAck);
  EXPECT_EQ(temps[0], -40);
  EXPECT_EQ(temps[1], 125);
}

// Chunks are served from a resume point when asked in order; any order must give the same bytes.
TEST_F(Session, ChunksInAnyOrderAndSizeReassembleTheSameDescriptor) {
  link();
  std::string inOrder = descriptor();
  std::string shuffled(inOrder.size(), '?');
  // Pieces of varied sizes covering the whole descriptor, asked for in a scrambled order.
  std::vector<std::pair<uint16_t, uint8_t>> pieces;
  const uint8_t wants[] = {5, 1, 28, 13, 20, 7};
  for (uint16_t off = 0, k = 0; off < inOrder.size(); off = (uint16_t)(off + wants[k++ % 6]))
    pieces.push_back({off, wants[k % 6]});
  std::mt19937 rng(7);
  std::shuffle(pieces.begin() + 1, pieces.end() - 3, rng);  // keep some in-order runs too
  for (auto& piece : pieces) {
    Bytes req(3);
    storeU16(&req[0], piece.first);
    req[2] = piece.second;
    RxFrame f = transact('J', 0, req);
    ASSERT_EQ(f.type, 'J');
    ASSERT_EQ(loadU16(&f.payload[0]), piece.first);
    shuffled.replace(piece.first, f.payload.size() - 4, std::string(f.payload.begin() + 4, f.payload.end()));
  }
  EXPECT_EQ(shuffled.find('?'), std::string::npos) << "some bytes never came";
  EXPECT_EQ(shuffled, inOrder);
}

// Found by fuzzing: a hub announcing a tiny accepted payload must not make the chunk size wrap
// (it overran the frame buffer). Payloads below a hello's 16 bytes are taken as 16.
TEST_F(Session, TinyAnnouncedPayloadStillGivesBoundedChunks) {
  drain(stream);
  Bytes hello = hubHello(31);
  storeU16(&hello[6], 2);
  sendFrame(stream, '*', 0, 0, hello);
  pump();
  ASSERT_TRUE(device.linked());
  Bytes req(3);
  req[2] = 255;
  RxFrame f = transact('J', 0, req);
  ASSERT_EQ(f.type, 'J');
  EXPECT_EQ(f.payload.size(), (size_t)kHelloSize);
  speed = 0.5f;
  EXPECT_EQ(transact('R', kSpeed).payload, le<float>(0.5f));  // state intact
}

TEST_F(Session, ChunksRespectTheWantedSizeAndOffsets) {
  link();
  Bytes req(3);
  storeU16(&req[0], 5);
  req[2] = 7;
  RxFrame f = transact('J', 0, req);
  ASSERT_EQ(f.type, 'J');
  EXPECT_EQ(f.payload.size(), 4u + 7u);
  storeU16(&req[0], device.descriptorLength());
  f = transact('J', 0, req);
  EXPECT_EQ(f.payload.size(), 4u);  // offset == total: empty chunk
  storeU16(&req[0], (uint16_t)(device.descriptorLength() + 1));
  expectNak(transact('J', 0, req), kErrBadOffset);
  expectNak(transact('J', 0, Bytes(2)), kErrBadLength);
}

TEST_F(Session, TransactionsBeforeHandshakeAreNakedNotLinked) {
  drain(stream);
  expectNak(transact('R', kSpeed), kErrNotLinked);
  expectNak(transact('C', kSpeed, le<float>(0.5f)), kErrNotLinked);
  EXPECT_EQ(speed, 0);
}

TEST_F(Session, ReadReturnsValuesOfEveryShape) {
  link();
  speed = 0.25f;
  RxFrame f = transact('R', kSpeed);
  EXPECT_EQ(f.type, 'r');
  EXPECT_EQ(f.payload, le<float>(0.25f));
  counts[0] = -1;
  counts[2] = 300;
  f = transact('R', kCounts);
  EXPECT_EQ(toHex(f.payload.data(), f.payload.size()), "ffff00002c01");
  f = transact('R', kLabel);
  EXPECT_EQ(toHex(f.payload.data(), f.payload.size()), "026869");
  pose.x = 1.0f;
  pose.ok = 1;
  pose.t[0] = 2;
  pose.t[1] = -2;
  f = transact('R', kPose);
  EXPECT_EQ(toHex(f.payload.data(), f.payload.size()), "0000803f010200feff");  // packed, no padding
}

TEST_F(Session, ReadErrors) {
  link();
  expectNak(transact('R', 99), kErrUnknownChannel);
  expectNak(transact('R', 0), kErrUnknownChannel);
  expectNak(transact('R', kLed), kErrNotReadable);
  expectNak(transact('R', kSpeed, Bytes(1)), kErrBadLength);
  // a window request (PROTOCOL.md 12.8) is answered only by a sketch with a large value
  EXPECT_EQ(hubwire_channels_tester::features & kUsesLarge, 0);
  EXPECT_EQ((HubwireLarge<true, void>::send), nullptr);
  expectNak(transact('R', kSpeed, Bytes{0, 0, 4, 0}), kErrBadLength);
}

TEST_F(Session, WriteStoresCallsBackAndAcks) {
  link();
  RxFrame f = transact('C', kSpeed, le<float>(-0.5f));
  EXPECT_EQ(f.type, kMsgAck);
  EXPECT_TRUE(f.payload.empty());
  EXPECT_EQ(speed, -0.5f);
  EXPECT_EQ(changes, 1);
  EXPECT_EQ(transact('C', kLabel, hex("03616263")).type, kMsgAck);
  EXPECT_STREQ(label, "abc");
  EXPECT_EQ(transact('C', kPose, hex("0000004001050006ff")).type, kMsgAck);
  EXPECT_EQ(pose.x, 2.0f);
  EXPECT_EQ(pose.t[0], 5);
  EXPECT_EQ(pose.t[1], (int16_t)0xFF06);
}

TEST_F(Session, WriteErrorsLeaveTheValueAlone) {
  link();
  speed = 0.1f;
  expectNak(transact('C', kSpeed, le<float>(1.5f)), kErrOutOfRange);
  expectNak(transact('C', kSpeed, le<float>(NAN)), kErrOutOfRange);  // NaN is in no range
  expectNak(transact('C', kSpeed, Bytes(3)), kErrBadLength);
  expectNak(transact('C', kCounts, Bytes(6)), kErrNotWritable);
  expectNak(transact('C', 77, Bytes(1)), kErrUnknownChannel);
  expectNak(transact('C', kLamp, Bytes(1, 2)), kErrBadValue);
  expectNak(transact('C', kLabel, hex("09414141414141414141")), kErrBadValue);  // 9 > capacity 8
  expectNak(transact('C', kLabel, hex("0341")), kErrBadLength);
  EXPECT_EQ(speed, 0.1f);
  EXPECT_EQ(changes, 0);
}

// Float ranges are compared on the floats' bits (channel.h): the same verdicts as float comparison.
TEST_F(Session, FloatRangeJudgedAsFloatComparisonWould) {
  link();
  for (float in : {-1.0f, 1.0f, 0.0f, -0.0f, 0.5f, -0.5f, 1e-40f, -1e-40f, 0.99999994f, -0.99999994f}) {
    EXPECT_EQ(transact('C', kSpeed, le<float>(in)).type, kMsgAck) << in;
    EXPECT_EQ(speed, in);
  }
  for (float out : {1.0000001f, -1.0000001f, 2.0f, -2.0f, INFINITY, -INFINITY, NAN, -NAN, 3e38f, -3e38f})
    expectNak(transact('C', kSpeed, le<float>(out)), kErrOutOfRange);
}

TEST_F(Session, ControlCallsTheFunctionAndMayRefuse) {
  link();
  EXPECT_EQ(transact('C', kLed, Bytes(1, 9)).type, kMsgAck);
  EXPECT_EQ(lastLed, 9);
  EXPECT_EQ(transact('C', kEven, le<uint16_t>(4)).type, kMsgAck);
  expectNak(transact('C', kEven, le<uint16_t>(5)), kErrRejected);
}

TEST_F(Session, ActionsReturnValuesOrAck) {
  link();
  RxFrame f = transact('C', kPing, le<int16_t>(-21));
  EXPECT_EQ(f.type, 'r');
  EXPECT_EQ(f.payload, le<int32_t>(-42));
  EXPECT_EQ(transact('C', kReset).type, kMsgAck);
  EXPECT_EQ(pingCalls, 2);
  expectNak(transact('C', kPing, Bytes(1)), kErrBadLength);
  expectNak(transact('R', kPing), kErrNotReadable);
}

TEST_F(Session, RetriedControlIsAnsweredAgainButAppliedOnce) {
  link();
  RxFrame a = transact('C', kPing, le<int16_t>(5), 40);
  RxFrame b = transact('C', kPing, le<int16_t>(5), 40);
  EXPECT_EQ(pingCalls, 1);
  EXPECT_EQ(a.type, b.type);
  EXPECT_EQ(a.payload, b.payload);
  transact('C', kSpeed, le<float>(0.5f), 41);
  transact('C', kSpeed, le<float>(0.5f), 41);
  EXPECT_EQ(changes, 1);
  // The NAK of a refused control is remembered as well.
  expectNak(transact('C', kEven, le<uint16_t>(3), 42), kErrRejected);
  expectNak(transact('C', kEven, le<uint16_t>(3), 42), kErrRejected);
}

TEST_F(Session, SameSeqAfterAnotherTransactionIsANewControl) {
  link();
  transact('C', kPing, le<int16_t>(1), 50);
  transact('R', kSpeed, Bytes(), 51);
  transact('C', kPing, le<int16_t>(1), 50);
  EXPECT_EQ(pingCalls, 2);
}

TEST_F(Session, NewHubSessionForgetsDuplicates) {
  link(1);
  transact('C', kPing, le<int16_t>(1), 60);
  link(2);
  transact('C', kPing, le<int16_t>(1), 60);
  EXPECT_EQ(pingCalls, 2);
}

TEST_F(Session, HeartbeatsCarryCounterIntervalAndErrorCounters) {
  link();  // the first heartbeat goes out with the hello
  auto f = linkFrames;
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[1].type, 'H');
  f.erase(f.begin());
  EXPECT_EQ(loadU16(&f[0].payload[0]), 1);
  EXPECT_EQ(loadU16(&f[0].payload[2]), 0);
  stream.in.push_back(0x05);  // garbage: one dropped frame
  stream.in.push_back(0x00);
  sendFrame(stream, 'H', 0, 0, Bytes(10));
  EXPECT_TRUE(pump(HUBWIRE_HEARTBEAT_MS - 1).empty());
  f = pump(1);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].seq, 2);
  EXPECT_EQ(loadU16(&f[0].payload[0]), 2);
  EXPECT_EQ(loadU16(&f[0].payload[2]), HUBWIRE_HEARTBEAT_MS);
  EXPECT_EQ(loadU16(&f[0].payload[8]), 1);  // dropped
}

TEST_F(Session, SilenceLosesTheLinkAppliesFailsafesAndCallsTheHook) {
  link();
  transact('C', kSpeed, le<float>(0.75f));
  transact('C', kLamp, Bytes(1, 0));
  pump(999);
  EXPECT_TRUE(device.linked());
  sendFrame(stream, 'H', 0, 0, Bytes(10));  // any frame keeps it alive
  pump(500);
  pump(500);
  EXPECT_TRUE(device.linked());
  pump(500);
  EXPECT_FALSE(device.linked());
  EXPECT_EQ(lostCalls, 1);
  EXPECT_EQ(speed, 0.0f);
  EXPECT_TRUE(lamp);
  EXPECT_EQ(temps[0], -40);  // every element of an array
  EXPECT_EQ(temps[1], -40);
  // The hub's next heartbeat gets a hello back, inviting it to handshake again.
  sendFrame(stream, 'H', 0, 0, Bytes(10));
  auto f = pump();
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].type, '*');
  EXPECT_EQ(f[0].payload[1] & kHelloReply, 0);
  expectNak(transact('R', kSpeed), kErrNotLinked);
  link();
  EXPECT_EQ(upCalls, 2);
}

// A control with a failsafe value is called with it when the link is lost: a motor driven through a
// function stops like one driven through a variable.
uint8_t motor;
int motorCalls;
void setMotor(uint8_t v) {
  motor = v;
  ++motorCalls;
}
HUBWIRE_CHANNELS(motorSketch, "tester", control("motor", setMotor).failsafe(0));

TEST(Failsafe, ControlIsCalledWithItsFailsafeWhenTheLinkIsLost) {
  motorCalls = 0;
  Boot b(motorSketch);
  ASSERT_TRUE(b.begun);
  ASSERT_TRUE(b.link());
  FakeStream& s = b.stream;
  FakeClock& c = b.clock;
  hubwire::Session& d = b.device;
  sendFrame(s, 'C', 1, 1, Bytes(1, 9));
  d.update();
  EXPECT_EQ(motor, 9);
  c.now += 1000;  // silence: 4 x the hub's 250 ms heartbeat
  d.update();
  EXPECT_FALSE(d.linked());
  EXPECT_EQ(motor, 0);
  EXPECT_EQ(motorCalls, 2);
}

// A hub that accepts 16-byte payloads is never sent a longer one (PROTOCOL 1): reading or subscribing
// to a 24-byte value is refused with BAD_LENGTH instead.
float wide[6];
HUBWIRE_CHANNELS(wideSketch, "tester", expose("wide", wide).streamable());

TEST(PeerMaximum, ValuesLongerThanTheHubAcceptsAreRefused) {
  Boot b(wideSketch);
  ASSERT_TRUE(b.begun);
  ASSERT_TRUE(b.link(16));
  FakeStream& s = b.stream;
  FakeClock& c = b.clock;
  hubwire::Session& d = b.device;
  drain(s);
  sendFrame(s, 'R', 1, 1);
  sendFrame(s, 'S', 2, 1, le<uint16_t>(50));
  d.update();
  c.now += 100;
  d.update();
  std::vector<RxFrame> answers;
  for (auto& f : drain(s)) {
    EXPECT_LE(f.payload.size(), 16u) << f.type;
    if (f.type != 'H') answers.push_back(f);
  }
  ASSERT_EQ(answers.size(), 2u);
  for (auto& a : answers) {
    EXPECT_EQ(a.type, kMsgNak);
    EXPECT_EQ(a.payload, Bytes{kErrBadLength});
  }
}

TEST_F(Session, LinkLossTimeoutFollowsTheHubsHeartbeat) {
  drain(stream);
  sendFrame(stream, '*', 0, 0, hubHello(3, 0, 1, 100));
  pump();
  pump(399);
  EXPECT_TRUE(device.linked());
  pump(1);
  EXPECT_FALSE(device.linked());
}

// A session starts with all its state zero, the receiver's included, wherever it is built: the
// Arduino face's global starts in zeroed memory, a local or a test's object does not.
TEST_F(Session, ASessionBuiltOverDirtyMemoryStartsClean) {
  alignas(hubwire::Session) unsigned char mem[sizeof(hubwire::Session)];
  memset(mem, 0xA5, sizeof(mem));
  hubwire::Session* s = new (mem) hubwire::Session(port);
  EXPECT_EQ(s->counters().crc, 0);
  EXPECT_EQ(s->counters().overflow, 0);
  EXPECT_EQ(s->counters().dropped, 0);
  EXPECT_EQ(s->eventsQueued(), 0);
  ASSERT_TRUE(s->begin(tester, 1));
  drain(stream);
  sendFrame(stream, '*', 0, 0, hubHello(5));
  s->update();
  EXPECT_TRUE(s->linked());
  EXPECT_EQ(s->counters().dropped, 0);
  s->~Session();
}

// Session times are 16-bit milliseconds: a slow hub's timeout is capped just below 65.5 s, and
// still measured exactly across the 16-bit wrap of millis().
// One buffer receives and sends: a frame of our own (here a heartbeat) waits while a hub frame is
// half received, and both arrive intact.
TEST_F(Session, OwnFramesWaitForAFrameStillArriving) {
  link();
  speed = 0.25f;
  uint8_t wire[64];
  size_t n = encodeFrame('R', 41, kSpeed, nullptr, 0, wire);
  stream.in.insert(stream.in.end(), wire, wire + 3);
  EXPECT_TRUE(pump(HUBWIRE_HEARTBEAT_MS).empty());  // a heartbeat is due, but the buffer is in use
  stream.in.insert(stream.in.end(), wire + 3, wire + n);
  auto sent = pump(1);
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].type, 'r');
  EXPECT_EQ(sent[0].seq, 41);
  EXPECT_EQ(sent[0].payload, le<float>(0.25f));
  EXPECT_EQ(sent[1].type, 'H');
  EXPECT_EQ(device.counters().dropped, 0);
}

// A frame whose sender stops halfway does not silence the device: after 50 ms it is dropped,
// counted, and the device's own frames flow again.
TEST_F(Session, AStalledFrameIsDroppedAndCounted) {
  link();
  uint8_t wire[64];
  size_t n = encodeFrame('R', 42, kSpeed, nullptr, 0, wire);
  stream.in.insert(stream.in.end(), wire, wire + 3);
  EXPECT_TRUE(pump(HUBWIRE_HEARTBEAT_MS).empty());
  EXPECT_TRUE(pump(49).empty());  // 49 ms after its last byte: still waiting
  auto sent = pump(1);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].type, 'H');
  EXPECT_EQ(device.counters().dropped, 1);
  stream.in.insert(stream.in.end(), wire + 3, wire + n);  // the rest arrives late: not a frame
  EXPECT_TRUE(pump().empty());
  EXPECT_EQ(transact('R', kSpeed).type, 'r');  // and the next request is answered
}

TEST_F(Session, SlowHubHeartbeatIsCappedBelowTheSixteenBitClock) {
  clock.now = 0xFFFF0000u - 5;
  drain(stream);
  sendFrame(stream, '*', 0, 0, hubHello(3, 0, 1, 60000));
  pump();
  const uint32_t cap = 65535u / HUBWIRE_LOST_AFTER_BEATS * HUBWIRE_LOST_AFTER_BEATS;
  pump(cap - 1);
  EXPECT_TRUE(device.linked());
  pump(1);
  EXPECT_FALSE(device.linked());
}

TEST_F(Session, EventsAreRetriedWithTheSameSeqUntilAcked) {
  link();
  pump();  // first heartbeat
  EXPECT_TRUE(device.emit(alarm, 513));
  auto f = pump();
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].type, '!');
  EXPECT_EQ(f[0].id, kAlarm);
  EXPECT_EQ(f[0].payload, le<uint16_t>(513));
  uint8_t first = f[0].seq;
  EXPECT_TRUE(pump(HUBWIRE_EVENT_RETRY_MS - 1).empty());
  f = pump(1);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].seq, first);
  sendFrame(stream, kMsgAck, (uint8_t)(first + 1), kAlarm);  // wrong seq: ignored
  pump();
  EXPECT_EQ(device.eventsQueued(), 1);
  sendFrame(stream, kMsgAck, first, kAlarm);
  pump();
  EXPECT_EQ(device.eventsQueued(), 0);
  EXPECT_TRUE(pump(HUBWIRE_EVENT_RETRY_MS).size() <= 1);  // at most a heartbeat
  device.emit(alarm, 1);
  f = pump();
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].seq, (uint8_t)(first + 1));
}

// The hub may have delivered the event whose ACK was lost with the link: after the relink the same
// event goes out with the same seq, so that the hub re-acks it instead of delivering it twice.
TEST_F(Session, EventResentAfterARelinkKeepsItsSeq) {
  link(77);
  pump();
  ASSERT_TRUE(device.emit(alarm, 5));
  std::vector<uint8_t> seqs;
  for (auto& f : pump())
    if (f.type == '!') seqs.push_back(f.seq);
  pump(1000);  // the hub went silent: link lost, event unacknowledged
  ASSERT_FALSE(device.linked());
  link(77);  // the same hub session comes back
  for (auto& f : linkFrames)
    if (f.type == '!') seqs.push_back(f.seq);
  ASSERT_EQ(seqs.size(), 2u);
  EXPECT_EQ(seqs[1], seqs[0]);
}

TEST_F(Session, EventsWaitForTheLinkAndTheQueueHasALimit) {
  drain(stream);
  for (int i = 0; i < HUBWIRE_EVENT_QUEUE; ++i) EXPECT_TRUE(device.emit(alarm, (uint16_t)i));
  EXPECT_FALSE(device.emit(alarm, 99));
  EXPECT_TRUE(pump().empty());  // not linked: kept, not sent
  link();
  std::vector<uint16_t> got;
  std::vector<RxFrame> frames = linkFrames;  // the first event leaves right after the hello
  for (int i = 0; i < 10 && got.size() < HUBWIRE_EVENT_QUEUE; ++i) {
    for (auto& f : frames) {
      if (f.type != '!') continue;
      got.push_back(loadU16(f.payload.data()));
      sendFrame(stream, kMsgAck, f.seq, f.id);
    }
    frames = pump(1);
  }
  EXPECT_EQ(got, (std::vector<uint16_t>{0, 1, 2, 3}));
}

TEST_F(Session, NakedEventIsNotRetried) {
  link();
  device.emit(alarm, 7);
  auto f = pump();
  uint8_t s = 0;
  for (auto& x : f)
    if (x.type == '!') s = x.seq;
  sendFrame(stream, kMsgNak, s, kAlarm, Bytes(1, kErrUnknownChannel));
  pump();
  EXPECT_EQ(device.eventsQueued(), 0);
}

TEST_F(Session, SubscribeStreamsSamplesAtTheGrantedInterval) {
  link();
  pump();
  RxFrame ack = transact('S', kSpeed, le<uint16_t>(50));
  EXPECT_EQ(ack.type, kMsgAck);
  EXPECT_EQ(ack.payload, le<uint16_t>(50));
  speed = 0.5f;
  std::vector<RxFrame> samples;
  for (auto& f : others)  // the first sample leaves with the ACK
    if (f.type == 'D') samples.push_back(f);
  for (int ms = 0; ms < 160; ++ms)
    for (auto& f : pump(1))
      if (f.type == 'D') samples.push_back(f);
  ASSERT_EQ(samples.size(), 4u);  // at 0, 50, 100, 150 ms
  EXPECT_EQ(samples[0].id, kSpeed);
  EXPECT_EQ(loadU16(&samples[0].payload[0]), 0);
  EXPECT_EQ(loadU16(&samples[1].payload[0]), 50);
  EXPECT_EQ(samples[1].seq, (uint8_t)(samples[0].seq + 1));
  EXPECT_EQ(Bytes(samples[2].payload.begin() + 2, samples[2].payload.end()), le<float>(0.5f));
  // Cancel.
  EXPECT_EQ(transact('S', kSpeed, le<uint16_t>(0)).payload, le<uint16_t>(0));
  for (int ms = 0; ms < 100; ++ms)
    for (auto& f : pump(1)) EXPECT_NE(f.type, 'D');
}

// Intervals past half the device's 16-bit millisecond clock (32.8 s) keep their schedule too: the
// first sample leaves at once, the next one interval later, not one on every update. The longest
// granted is 60 s, so that an update() up to 5.5 s late still sees a sample fall due.
TEST_F(Session, LongStreamIntervalsKeepTheirSchedule) {
  link();
  for (uint32_t asked : {40000u, 65535u}) {
    uint32_t interval = std::min(asked, 60000u);
    EXPECT_EQ(transact('S', kSpeed, le<uint16_t>((uint16_t)asked)).payload, le<uint16_t>((uint16_t)interval));
    std::vector<uint32_t> at;  // when each sample left, in ms after the subscription
    for (auto& f : others)
      if (f.type == 'D') at.push_back(0);
    for (uint32_t t = 100; t <= 2 * interval + 50; t += 100) {
      sendFrame(stream, 'H', 0, 0, Bytes(10, 0));  // the hub stays alive
      for (auto& f : pump(100))
        if (f.type == 'D') at.push_back(t);
    }
    uint32_t step = (interval + 99) / 100 * 100;  // updates run every 100 ms
    EXPECT_EQ(at, (std::vector<uint32_t>{0, step, (2 * interval + 99) / 100 * 100})) << interval;
    transact('S', kSpeed, le<uint16_t>(0));
  }
}

// Subscribing again changes the interval of the same subscription: its next sample still reports the
// time since the previous one (PROTOCOL 3.7), and its seq goes on.
TEST_F(Session, ResubscribingKeepsTheTimeSinceThePreviousSample) {
  link();
  pump();
  transact('S', kSpeed, le<uint16_t>(50));  // a sample at once
  std::vector<RxFrame> samples;
  for (int ms = 0; ms < 60; ++ms)
    for (auto& f : pump(1))
      if (f.type == 'D') samples.push_back(f);
  ASSERT_EQ(samples.size(), 1u);  // at 50 ms
  transact('S', kSpeed, le<uint16_t>(20));  // at 60 ms: the next sample leaves at once
  for (auto& f : others)
    if (f.type == 'D') samples.push_back(f);
  ASSERT_EQ(samples.size(), 2u);
  EXPECT_EQ(loadU16(&samples[1].payload[0]), 10);
  EXPECT_EQ(samples[1].seq, (uint8_t)(samples[0].seq + 1));
}

TEST_F(Session, SubscribeClampsChecksAndRunsOutOfSlots) {
  link();
  EXPECT_EQ(transact('S', kSpeed, le<uint16_t>(1)).payload, le<uint16_t>(HUBWIRE_MIN_STREAM_INTERVAL_MS));
  expectNak(transact('S', kLabel, le<uint16_t>(100)), kErrNotStreamable);
  expectNak(transact('S', 99, le<uint16_t>(100)), kErrUnknownChannel);
  expectNak(transact('S', kCounts, Bytes(1)), kErrBadLength);
  EXPECT_EQ(transact('S', kCounts, le<uint16_t>(100)).type, kMsgAck);
#if HUBWIRE_MAX_STREAMS == 2
  // A third channel would need a third slot; re-subscribing an active one does not.
  EXPECT_EQ(transact('S', kSpeed, le<uint16_t>(30)).type, kMsgAck);
#endif
}

TEST_F(Session, SamplesWaitForRoomInTheOutputBuffer) {
  link();
  pump();
  transact('S', kSpeed, le<uint16_t>(20));
  stream.room = 5;
  for (auto& f : pump(1)) EXPECT_NE(f.type, 'D');
  for (auto& f : pump(30)) EXPECT_NE(f.type, 'D');  // due, but no room
  stream.room = 4096;
  bool got = false;
  for (auto& f : pump(1)) got |= f.type == 'D';
  EXPECT_TRUE(got);
}

TEST_F(Session, StreamsEndWithTheLink) {
  link();
  transact('S', kSpeed, le<uint16_t>(20));
  pump(2000);
  link();
  for (int ms = 0; ms < 100; ++ms)
    for (auto& f : pump(1)) EXPECT_NE(f.type, 'D');
}

TEST_F(Session, UnknownMessageTypeIsNaked) {
  link();
  expectNak(transact('Z', 1), kErrUnknownType);
  expectNak(transact('r', 1), kErrUnknownType);
}

// ---- declaration errors ----

// Every mistake in a declaration fails to compile (test/compile_fail). What is left for begin() to
// refuse is a table without channels.
HUBWIRE_CHANNELS(fine, "x", expose("fine", speed));

TEST(Declarations, AnEmptyTableIsRefusedAndTheDeviceStaysSilent) {
  FakeStream s;
  FakeClock c;
  Port p(s, c);
  hubwire::Session d(p);
  EXPECT_EQ(d.error(), kSetupNoDeclarations);  // begin() not called yet
  const ChannelTable empty = {nullptr, 0, 0, nullptr, 0};
  EXPECT_FALSE(d.begin(empty));
  EXPECT_EQ(d.error(), kSetupNoDeclarations);
  // Neither the announcement nor an answer to a hub: a device that failed begin() stays silent.
  c.now += HUBWIRE_ANNOUNCE_MS;
  sendFrame(s, '*', 0, 0, hubHello(8));
  d.update();
  EXPECT_TRUE(s.out.empty());
  EXPECT_FALSE(d.linked());
  // And a corrected sketch starts (and speaks, so the silence above was begin()'s doing).
  s.in.clear();
  EXPECT_TRUE(d.begin(fine));
  EXPECT_EQ(d.error(), kSetupOk);
  EXPECT_EQ(d.channelCount(), 1);
  c.now += HUBWIRE_ANNOUNCE_MS;
  d.update();
  auto f = drain(s);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].type, '*');
  // An empty table after a good one stops the device again.
  EXPECT_FALSE(d.begin(empty));
  EXPECT_EQ(d.error(), kSetupNoDeclarations);
  c.now += HUBWIRE_ANNOUNCE_MS;
  d.update();
  EXPECT_TRUE(s.out.empty());
}

// Descriptor numbers (min, max, fs) are printed by the compiler without floating-point arithmetic
// (constexpr_text.h); they must read back as the same f32 the sketch declared.
constexpr float kNumbers[] = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -0.25f, 0.7f, 0.1f, 3.3f, 5000.0f, 9.81f, 123456.789f,
                              -32768.0f, 65535.0f, 4294967295.0f, 1e20f, -3.4028235e38f, 1e-3f, 2.5e-5f, 0.0001f,
                              1e-14f, -1e-20f, 1.4e-45f};  // the last three print as 0 (six decimals)
const size_t kNumberCount = sizeof(kNumbers) / sizeof(kNumbers[0]);

// kNumbers[I] as the descriptor prints it, worked out by the compiler (constexpr: any part of
// the formatter that cannot run at compile time fails the build).
template <size_t I, typename S = typename cx::MakeSeq<cx::floatLength(kNumbers[I])>::type>
struct Printed;
template <size_t I, size_t... C>
struct Printed<I, cx::Seq<C...> > {
  static constexpr char text[sizeof...(C) + 1] = {cx::floatAt(kNumbers[I], C)..., 0};
};
template <size_t I, size_t... C>
constexpr char Printed<I, cx::Seq<C...> >::text[sizeof...(C) + 1];

template <size_t... I>
std::vector<std::string> printedNumbers(cx::Seq<I...>) {
  return {Printed<I>::text...};
}

TEST(JsonNumbers, ReadBackAsTheSameFloat) {
  std::vector<std::string> printed = printedNumbers(cx::MakeSeq<kNumberCount>::type());
  ASSERT_EQ(printed.size(), kNumberCount);
  for (size_t i = 0; i < kNumberCount; ++i) {
    float v = kNumbers[i];
    const std::string& text = printed[i];
    double back = nlohmann::json::parse(text).get<double>();
    EXPECT_NEAR(back, v, std::fabs(v) * 1e-6 + 1e-6) << text;
    if (std::fabs(v) < 1e9f && v == (float)(int32_t)v && !std::signbit(v)) {
      EXPECT_EQ(text, std::to_string((int32_t)v)) << text;
    }
    if (v == 0.7f) {
      EXPECT_EQ(text, "0.7");  // 0.699999988: rounds to 6 decimals, not truncated to 0.699999
    }
  }
}

}  // namespace

// One session per port: copying one (which would answer the same hub twice) does not compile.
TEST(Copying, IsRefused) {
  EXPECT_FALSE(std::is_copy_constructible<hubwire::Session>::value);
  EXPECT_FALSE(std::is_copy_assignable<hubwire::Session>::value);
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
