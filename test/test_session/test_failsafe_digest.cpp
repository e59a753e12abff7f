// Two parts of the device session, each against its own small sketch: a variable's failsafe acts as a
// hub's write would (its onChange runs with the failsafe value stored, once per link loss), and the
// hello carries the descriptor's digest to a hub that accepts it (PROTOCOL.md 3.1, 4.3).
#include <gtest/gtest.h>

#include <string>

#include "fakes.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"
#include "hubwire/wire/bytes.h"

using namespace hubwire;
using namespace hubwire::test;

namespace {

int16_t duty;
int dutyChanges, lostAt;
int16_t dutySeen;
FakeClock* slowClock;  // set: onChange takes 20 ms, as driving real hardware may
void dutyChanged() {
  ++dutyChanges;
  dutySeen = duty;  // what a motor driven from onChange would be given
  if (slowClock) slowClock->now += 20;
}
void probeLost() { lostAt = dutyChanges; }

HUBWIRE_CHANNELS(probe, "probe", expose("duty", duty).writable().failsafe(0).onChange(dutyChanged));

struct Probe {
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  hubwire::Session device{port};
  uint8_t seq = 0;
  Probe() {
    duty = 0;
    dutyChanges = lostAt = dutySeen = 0;
    slowClock = nullptr;
    device.onLinkLost(probeLost);
    EXPECT_TRUE(device.begin(probe, 7));
  }
  // A hub that accepts payloads of up to hubMax bytes says hello; the device's frames in answer.
  std::vector<RxFrame> hello(uint16_t hubMax = 255, uint32_t nonce = 5) {
    drain(stream);
    Bytes h = hubHello(nonce);
    storeU16(&h[6], hubMax);
    sendFrame(stream, '*', 0, 0, h);
    device.update();
    return drain(stream);
  }
  void write(int16_t v) {
    Bytes p(2);
    storeU16(&p[0], (uint16_t)v);
    sendFrame(stream, 'C', ++seq, 1, p);
    device.update();
    drain(stream);
  }
  // Silence for the device's whole timeout (4 x the hub's 250 ms heartbeat).
  void silence() {
    clock.now += 1000;
    device.update();
  }
  // The first hello among what the device sent since the last look.
  Bytes sentHello() {
    for (auto& f : drain(stream))
      if (f.type == '*') return f.payload;
    return Bytes();
  }
};

TEST(FailsafeOnChange, RunsWithTheFailsafeValueStoredBeforeTheLinkLostHook) {
  Probe p;
  p.hello();
  ASSERT_TRUE(p.device.linked());
  p.write(40);
  EXPECT_EQ(dutyChanges, 1);
  EXPECT_EQ(dutySeen, 40);
  p.silence();
  ASSERT_FALSE(p.device.linked());
  EXPECT_EQ(dutyChanges, 2);
  EXPECT_EQ(dutySeen, 0);  // the failsafe value was stored before onChange ran
  EXPECT_EQ(lostAt, 2);    // ... and onChange ran before the link-lost hook
  p.clock.now += 5000;     // once per link loss, not once per update()
  p.device.update();
  EXPECT_EQ(dutyChanges, 2);
}

// After a loss the device announces itself once per second (PROTOCOL.md 3, rule 3), counted from
// the update() that found the hub silent, even when the failsafes take time.
TEST(FailsafeOnChange, AnnouncementFollowsOneIntervalAfterTheLossEvenWhenFailsafesTakeTime) {
  Probe p;
  p.hello();
  slowClock = &p.clock;
  p.clock.now += 1000;  // silence for the whole timeout
  uint32_t lostAt = p.clock.now;
  p.device.update();
  ASSERT_FALSE(p.device.linked());
  EXPECT_EQ(p.clock.now, lostAt + 20);  // the failsafe's onChange took its time
  EXPECT_TRUE(p.sentHello().empty());   // not at once
  p.clock.now = lostAt + HUBWIRE_ANNOUNCE_MS - 1;
  p.device.update();
  EXPECT_TRUE(p.sentHello().empty());
  p.clock.now = lostAt + HUBWIRE_ANNOUNCE_MS;
  p.device.update();
  EXPECT_FALSE(p.sentHello().empty());
}

// The rule is a hub write's: a write of the value the variable already holds calls onChange too, and
// so does a failsafe that finds the value already there.
TEST(FailsafeOnChange, RunsEvenWhenTheValueIsAlreadyTheFailsafe) {
  Probe p;
  p.hello();
  p.write(0);
  p.write(0);
  EXPECT_EQ(dutyChanges, 2);
  p.silence();
  ASSERT_FALSE(p.device.linked());
  EXPECT_EQ(dutyChanges, 3);
  EXPECT_EQ(dutySeen, 0);
  p.hello(255, 6);  // a new hub session, which writes nothing
  ASSERT_TRUE(p.device.linked());
  p.silence();
  EXPECT_EQ(dutyChanges, 4);
}

Bytes digestInFlash(const ChannelTable& t) { return Bytes(t.json - kDigestSize, t.json); }

// hashlib.sha256(b'{"p":1,"n":"probe","ch":[{"id":1,"n":"duty","a":"rw","t":"i16","fs":0}]}').hexdigest()[:32]
TEST(HelloDigest, TheFirst16BytesOfTheDescriptorsSha256PrecedeTheJson) {
  EXPECT_EQ(std::string(probe.json, probe.jsonLength),
            R"({"p":1,"n":"probe","ch":[{"id":1,"n":"duty","a":"rw","t":"i16","fs":0}]})");
  EXPECT_EQ(toHex(digestInFlash(probe).data(), kDigestSize), "acc899d0357080500194e9d519b66f14");
}

TEST(HelloDigest, AnsweredToAHubThatAccepts32BytesOrMore) {
  for (uint16_t hubMax : {32, 33, 255, 1000}) {
    Probe p;
    auto frames = p.hello(hubMax);
    ASSERT_FALSE(frames.empty());
    ASSERT_EQ(frames[0].type, '*');
    const Bytes& h = frames[0].payload;
    ASSERT_EQ(h.size(), (size_t)kHelloDigestEnd) << hubMax;
    EXPECT_EQ(h[1], kHelloDevice | kHelloReply | kHelloSeqRules | (HUBWIRE_HAS_F64 ? kHelloF64 : 0));
    EXPECT_EQ(loadU32(&h[10]), probe.hash);  // the FNV hash stays where old hubs read it
    EXPECT_EQ(loadU16(&h[14]), probe.jsonLength);
    EXPECT_EQ(Bytes(h.begin() + kHelloSize, h.end()), digestInFlash(probe));
  }
}

// A hub that accepts less than 32 bytes gets the 16-byte hello it knows; so does a hub not heard yet
// (16 bytes is all a peer is sure to accept), while one heard before gets the digest again.
TEST(HelloDigest, NeverLongerThanThePeerAccepts) {
  for (uint16_t hubMax : {0, 16, 31}) {
    Probe p;
    auto frames = p.hello(hubMax);
    ASSERT_FALSE(frames.empty());
    EXPECT_EQ(frames[0].payload.size(), (size_t)kHelloSize) << hubMax;
    ASSERT_TRUE(p.device.linked());
    p.silence();
    p.clock.now += HUBWIRE_ANNOUNCE_MS;
    p.device.update();
    EXPECT_EQ(p.sentHello().size(), (size_t)kHelloSize) << hubMax;
  }
  Probe p;
  p.clock.now += HUBWIRE_ANNOUNCE_MS;
  p.device.update();
  EXPECT_EQ(p.sentHello().size(), (size_t)kHelloSize);  // the first announcement: no hub heard
  p.hello(64);
  p.silence();
  p.clock.now += HUBWIRE_ANNOUNCE_MS;
  p.device.update();
  Bytes again = p.sentHello();
  ASSERT_EQ(again.size(), (size_t)kHelloDigestEnd);
  EXPECT_EQ(Bytes(again.begin() + kHelloSize, again.end()), digestInFlash(probe));
}

}  // namespace
