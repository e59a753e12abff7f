// The device's one transaction counter (PROTOCOL 4.1) numbers its events, its M updates and its own
// requests to the hub: none of them may repeat a seq another still uses or used just before,
// whatever the order the hub answers in (an event acked in the update after it went, before the
// next look at the queue, was once such a case). With and without hub channels, which keep the
// counter in the hub link.
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "fixture.h"

using namespace hubwire;
using namespace hubwire::test;

// Without hub channels (lone_sketch.cpp: one table with missions a file).
extern Mission<uint8_t(uint8_t), uint16_t> lift;  // id 1
extern Event<uint16_t> tick;                      // id 2
const ChannelTable& loneTable();
bool startLift(uint8_t);
extern int liftStarts;
void cancelLift();

Mission<uint8_t(uint8_t), uint16_t> crane;  // id 1
Event<uint16_t> tock;                       // id 2
float setpoint;                              // hub id 1
HUBWIRE_CHANNELS(linked, "linked", mission("crane", crane, startLift, cancelLift), event("tock", tock),
                 remote("setpoint", setpoint));

namespace {

struct Sent {
  uint8_t type, seq, id;
  Bytes payload;
  bool operator<(const Sent& o) const {
    return std::tie(type, seq, id, payload) < std::tie(o.type, o.seq, o.id, o.payload);
  }
};

class SeqTest : public MissionHub {
 protected:
  // Runs the device with events, progress and (with hub channels) requests, the hub answering each
  // at once, one update later, or not at all (then the device retries); every distinct frame the
  // device originated must hold a seq of its own.
  void soak(Mission<uint8_t(uint8_t), uint16_t>& m, Event<uint16_t>& ev, bool requests, unsigned seed) {
    std::mt19937 rng(seed);
    std::set<Sent> distinct;
    std::vector<RxFrame> held;  // answered one update later
    uint16_t value = 0;
    int delivered = 0;
    for (int i = 0; i < 2000 && distinct.size() < 200; ++i) {
      unsigned r = rng();
      if (r % 3 == 0) device.emit(ev, ++value);
      if (r % 2 == 0) device.progress(m, ++value);
      if (requests && r % 5 == 0) device.request(setpoint);
      for (auto& f : held) answer(f);
      held.clear();
      for (auto& f : step(r % 4 == 0 ? HUBWIRE_EVENT_RETRY_MS : 5)) {
        if (f.type != kMsgEvent && f.type != kMsgMission && f.type != kMsgRequest) continue;
        distinct.insert(Sent{f.type, f.seq, f.id, f.payload});
        unsigned how = rng() % 3;
        if (how == 0) answer(f);
        else if (how == 1) held.push_back(f);
      }
      if (r % 16 == 0) sendFrame(stream, kMsgHeartbeat, 0, 0, Bytes(kHeartbeatSize, 0));
    }
    std::map<uint8_t, Sent> bySeq;
    for (auto& s : distinct) {
      auto it = bySeq.find(s.seq);
      EXPECT_TRUE(it == bySeq.end()) << "seq " << (int)s.seq << " numbers two frames: type " << (int)s.type
                                     << " and type " << (int)(it == bySeq.end() ? 0 : it->second.type);
      bySeq[s.seq] = s;
      delivered += s.type != kMsgRequest;
    }
    EXPECT_GE(distinct.size(), 150u);
    EXPECT_GT(delivered, 100);
  }
  void answer(const RxFrame& f) {
    if (f.type == kMsgRequest) sendFrame(stream, kMsgResponse, f.seq, f.id, le(1.0f));
    else sendFrame(stream, kMsgAck, f.seq, f.id);
  }
};

TEST_F(SeqTest, EventsAndUpdatesNeverShareASeq) {
  ASSERT_TRUE(device.begin(loneTable(), 1));
  lift = decltype(lift)();
  link();
  ASSERT_EQ(start(1, Bytes{3}).type, kMsgResponse);
  for (unsigned seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    soak(lift, tick, false, seed);
  }
}

TEST_F(SeqTest, EventsUpdatesAndHubRequestsNeverShareASeq) {
  ASSERT_TRUE(device.begin(linked, 1));
  crane = decltype(crane)();
  link();
  ASSERT_EQ(ask(kMsgControl, ++hubSeq, 0, Bytes{1, 0}).type, kMsgAck);  // the bind report
  ASSERT_EQ(start(1, Bytes{3}).type, kMsgResponse);
  for (unsigned seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    soak(crane, tock, true, seed);
  }
}

// The case spelled out: an event sent and acked before the next poll; then an update and an event
// numbered in the same update.
TEST_F(SeqTest, AnEventAckedBeforeTheNextPollLeavesItsSeqBehind) {
  ASSERT_TRUE(device.begin(loneTable(), 1));
  lift = decltype(lift)();
  link();
  ASSERT_EQ(start(1, Bytes{3}).type, kMsgResponse);
  std::vector<uint8_t> seqs;
  device.emit(tick, 1);
  auto e = only(step(), kMsgEvent);
  ASSERT_EQ(e.size(), 1u);
  seqs.push_back(e[0].seq);
  ack(e[0]);
  device.progress(lift, 7);
  device.emit(tick, 2);
  auto out = step();
  auto m = only(out, kMsgMission);
  auto e2 = only(out, kMsgEvent);
  ASSERT_EQ(m.size(), 1u);
  ASSERT_EQ(e2.size(), 1u);
  seqs.push_back(m[0].seq);
  seqs.push_back(e2[0].seq);
  ack(m[0]);
  ack(e2[0]);
  device.emit(tick, 3);
  auto e3 = only(step(), kMsgEvent);
  ASSERT_EQ(e3.size(), 1u);
  seqs.push_back(e3[0].seq);
  for (size_t i = 1; i < seqs.size(); ++i) EXPECT_EQ(seqs[i], (uint8_t)(seqs[i - 1] + 1)) << i;
}

// The hub link restores the duplicate-control memory after an answer to the device's own chunk
// request: a start before it must stay the control a retry is matched against.
TEST_F(SeqTest, AHubChunkBetweenAStartAndItsRetryKeepsItExactlyOnce) {
  ASSERT_TRUE(device.begin(linked, 1));
  crane = decltype(crane)();
  liftStarts = 0;
  link();
  ASSERT_EQ(ask(kMsgControl, ++hubSeq, 0, Bytes{1, 0}).type, kMsgAck);
  ASSERT_TRUE(device.readHubDescriptor(0, [](uint16_t, uint16_t, const uint8_t*, uint8_t) {}));
  auto j = only(step(), kMsgChunk);
  ASSERT_EQ(j.size(), 1u);
  RxFrame a = start(1, Bytes{3});
  ASSERT_EQ(a.payload, Bytes{1});
  uint8_t seq = hubSeq;
  sendFrame(stream, kMsgChunk, j[0].seq, 0, Bytes{0, 0, 2, 0, '{', '}'});
  step();
  RxFrame again = ask(kMsgControl, seq, 1, Bytes{kMissionStart, 3});  // its answer was lost
  EXPECT_EQ(again.type, kMsgResponse);
  EXPECT_EQ(again.payload, Bytes{1});
  EXPECT_EQ(liftStarts, 1);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
