// A model of the hub's duplicate memories (PROTOCOL.md 4.4, 10.2, 11.3) driven by the device's real
// session: random bursts of events, mission updates, writes to the hub and reads of it, every frame
// and every answer sometimes lost, for long enough that the device's 8-bit transaction counter wraps
// many times in every mix. Each message carries a token of its own, so the test knows the truth: a
// message the hub's memory takes for a repeat must be one it applied already (else it was lost after
// an ACK), and one it takes for new must not be (else it was applied twice).
#include <cstdlib>
#include <map>
#include <random>
#include <set>

#include "../test_missions/fixture.h"
#include "hubwire/wire/bytes.h"

using namespace hubwire;
using namespace hubwire::test;

Mission<uint16_t(uint8_t), uint16_t> job;  // id 1
Event<uint16_t> note;                      // id 2
uint16_t report;                           // hub id 1: the device writes it
uint16_t hubLevel;                           // hub id 2: the device reads it
bool startJob(uint8_t) { return true; }
void cancelJob() {}
HUBWIRE_CHANNELS(wrapped, "wrapped", mission("job", job, startJob, cancelJob), event("note", note),
                 remote("report", report).writeOnly(), remote("hubLevel", hubLevel));

// Without hub channels: events and missions share the counter in the missions' run time.
extern Mission<uint16_t(uint8_t), uint16_t> lift;  // id 1 (lone.cpp)
extern Event<uint16_t> tick;                       // id 2
const ChannelTable& loneTable();

namespace {

int writesDone, writesFailed;
void writeDone() { ++writesDone; }
void writeFailed(uint8_t) { ++writesFailed; }

// The reference hub's memories, one per stream, and what it applied.
struct HubModel {
  bool eValid = false, mValid = false, cValid = false;
  uint8_t eSeq = 0, mSeq = 0, mId = 0, cSeq = 0, cId = 0;
  std::set<uint32_t> applied;  // tokens
  std::map<char, int> lost, twice, delivered;

  // Judges one message the way the hub does and checks the verdict against the truth.
  void judge(char kind, bool repeat, uint32_t token) {
    bool seen = applied.count(token) != 0;
    if (repeat && !seen) ++lost[kind];
    if (!repeat && seen) ++twice[kind];
    if (!repeat) {
      applied.insert(token);
      ++delivered[kind];
    }
  }
};

uint32_t tokenOf(char kind, uint16_t v) { return (uint32_t)kind << 16 | v; }

// Bursts a run plays: 400 in `make test`, HUBWIRE_WRAP_BURSTS for the long run (`make soak`).
int bursts() {
  const char* env = std::getenv("HUBWIRE_WRAP_BURSTS");
  return env ? std::atoi(env) : 400;
}

class WrapModel : public MissionHub {
 protected:
  HubModel hub;
  std::mt19937 rng;
  std::vector<std::pair<RxFrame, uint8_t>> answers;  // (question, answer type) sent next update
  uint16_t token = 0;
  uint32_t sinceBeat = 0;
  unsigned lossy = 0;
  int sent[256] = {};  // frames the device originated, by type

  template <typename M>
  void run(M& mission, Event<uint16_t>& ev, bool hubChannels, unsigned seed, int bursts) {
    rng.seed(seed);
    writesDone = writesFailed = 0;
    ASSERT_EQ(start(1, Bytes{1}).type, kMsgResponse);
    for (int b = 0; b < bursts; ++b) {
      unsigned kind = rng() % (hubChannels ? 4 : 2);
      // lengths around the counter's half and whole turns, where a wrap meets another stream
      static const unsigned kTurns[] = {1, 1, 2, 3, 127, 128, 129, 130, 254, 255, 256, 257};
      unsigned length = rng() % 2 ? kTurns[rng() % 12] : 1 + rng() % 300;
      lossy = rng() % 4;  // 0, 1: a clean link; 2: some frames lost; 3: most lost (requests time out)
      for (unsigned i = 0; i < length; ++i) {
        // Tokens are 16-bit values on the wire: one comes round every 65,536, long after any retry of
        // the message that had it, which the model forgets now.
        ++token;
        for (char k : {'e', 'm', 'c'}) hub.applied.erase(tokenOf(k, token));
        if (kind == 0) device.emit(ev, token);
        if (kind == 1) {
          if (rng() % 16 == 0) device.finish(mission, token);
          else device.progress(mission, token);
        }
        if (kind == 2) {
          report = token;
          device.write(report, writeDone, writeFailed);
        }
        if (kind == 3) device.request(hubLevel);
        // one message at a time: each burst's messages go out back to back, answered or retried
        for (int k = 0; k < 40 && busy(kind); ++k) exchange(mission);
        exchange(mission);
      }
    }
    for (int k = 0; k < 200; ++k) exchange(mission);  // the last ones out
  }

  bool busy(unsigned kind) {
    if (kind == 0) return device.eventsQueued() > 0;
    if (kind == 1) return missionLink.id != 0 || missionLink.pending;
    return device.hubQueued() > 0;
  }

  // One update of the device: the answers decided last time arrive, the device's frames reach the
  // hub or are lost, the hub judges them and decides their answers (some lost).
  template <typename M>
  void exchange(M& mission) {
    for (auto& a : answers) sendFrame(stream, a.second, a.first.seq, a.first.id, reply(a.first, a.second));
    answers.clear();
    uint32_t ms = lossy >= 2 && rng() % 8 == 0 ? HUBWIRE_EVENT_RETRY_MS : 2;
    sinceBeat += ms;
    if (sinceBeat >= 200) {  // keeps the link up whatever is lost
      sendFrame(stream, kMsgHeartbeat, 0, 0, Bytes(kHeartbeatSize, 0));
      sinceBeat = 0;
    }
    for (auto& f : step(ms)) {
      ++sent[f.type];
      if ((lossy == 2 && rng() % 12 == 0) || (lossy == 3 && rng() % 3 != 0)) continue;  // lost on the way
      uint8_t answer = receive(f);
      if (answer && (lossy < 2 || rng() % 8 != 0)) answers.push_back({f, answer});
    }
    if (!mission.running() && !(missionLink.id || missionLink.pending)) {
      RxFrame a = start(1, Bytes{1});  // the final is out: the next run
      for (auto& o : others) {
        if (o.type == kMsgMission || o.type == kMsgEvent) {
          uint8_t answer = receive(o);
          if (answer) answers.push_back({o, answer});
        }
      }
      (void)a;
    }
  }

  uint8_t receive(const RxFrame& f) {
    switch (f.type) {
      case kMsgEvent: {
        hub.judge('e', hub.eValid && f.seq == hub.eSeq, tokenOf('e', loadU16(f.payload.data())));
        hub.eValid = true;
        hub.eSeq = f.seq;
        return kMsgAck;
      }
      case kMsgMission: {
        bool repeat = hub.mValid && f.seq == hub.mSeq && f.id == hub.mId;
        if (f.payload.size() >= 4) hub.judge('m', repeat, tokenOf('m', loadU16(f.payload.data() + 2)));
        hub.mValid = true;
        hub.mSeq = f.seq;
        hub.mId = f.id;
        return kMsgAck;
      }
      case kMsgControl: {
        hub.judge('c', hub.cValid && f.seq == hub.cSeq && f.id == hub.cId, tokenOf('c', loadU16(f.payload.data())));
        hub.cValid = true;
        hub.cSeq = f.seq;
        hub.cId = f.id;
        return kMsgAck;
      }
      case kMsgRequest:
      case kMsgChunk:
        hub.cValid = false;  // any other device transaction ends the window of its last control
        return f.type == kMsgRequest ? kMsgResponse : kMsgChunk;
      default:
        return 0;
    }
  }

  static Bytes reply(const RxFrame& q, uint8_t type) {
    if (type == kMsgResponse) return le((uint16_t)7);
    if (type == kMsgChunk) return Bytes{0, 0, 2, 0};
    (void)q;
    return Bytes();
  }

  void expectExact() {
    int frames = sent[kMsgEvent] + sent[kMsgMission] + sent[kMsgControl] + sent[kMsgRequest] + sent[kMsgChunk];
    printf("delivered e=%d m=%d c=%d; sent e=%d m=%d c=%d r=%d j=%d; counter wraps %d; lost 0 twice 0 unless below\n",
           hub.delivered['e'], hub.delivered['m'], hub.delivered['c'], sent[kMsgEvent], sent[kMsgMission],
           sent[kMsgControl], sent[kMsgRequest], sent[kMsgChunk], frames / 256);
    for (char k : {'e', 'm', 'c'}) {
      EXPECT_EQ(hub.lost[k], 0) << k << ": new messages the hub took for repeats (lost after an ACK)";
      EXPECT_EQ(hub.twice[k], 0) << k << ": repeats the hub took for new messages (applied twice)";
    }
  }
};

TEST_F(WrapModel, WithHubChannelsEveryStreamExactlyOnceThroughManyWraps) {
  ASSERT_TRUE(device.begin(wrapped, 1));
  job = decltype(job)();
  link();
  ASSERT_EQ(ask(kMsgControl, ++hubSeq, 0, Bytes{1, 0, 0}).type, kMsgAck);  // the bind report
  run(job, note, true, 1, bursts());
  expectExact();
  int originated = sent[kMsgEvent] + sent[kMsgMission] + sent[kMsgControl] + sent[kMsgRequest];
  EXPECT_GE(originated / 256, 20) << "the transaction counter wrapped too few times to prove anything";
  EXPECT_GT(hub.delivered['e'], 1000);
  EXPECT_GT(hub.delivered['m'], 1000);
  EXPECT_GT(hub.delivered['c'], 1000);
  EXPECT_LE(writesDone, hub.delivered['c']);
  EXPECT_GT(writesFailed, 10) << "too few writes went unanswered to exercise the hub's memory after one";
  EXPECT_GT(sent[kMsgChunk], 0) << "no chunk request cleared the hub's memory after an unanswered write";
}

TEST_F(WrapModel, WithoutHubChannelsEventsAndUpdatesExactlyOnceThroughManyWraps) {
  ASSERT_TRUE(device.begin(loneTable(), 1));
  lift = decltype(lift)();
  link();
  run(lift, tick, false, 2, bursts());
  expectExact();
  EXPECT_GE((sent[kMsgEvent] + sent[kMsgMission]) / 256, 20);
}

// The two cases found from outside, spelled out on a clean link. Each message is answered at once.
class WrapCases : public WrapModel {
 protected:
  void SetUp() override {
    WrapModel::SetUp();
    ASSERT_TRUE(device.begin(wrapped, 1));
    job = decltype(job)();
    link();
    ASSERT_EQ(ask(kMsgControl, ++hubSeq, 0, Bytes{1, 0, 0}).type, kMsgAck);
    ASSERT_EQ(start(1, Bytes{1}).type, kMsgResponse);
    writesDone = writesFailed = 0;
  }
  // Runs updates, every frame reaching the hub and every answer the device, until nothing is out.
  void settle() {
    for (int k = 0; k < 8; ++k) {
      for (auto& a : answers) sendFrame(stream, a.second, a.first.seq, a.first.id, reply(a.first, a.second));
      answers.clear();
      for (auto& f : step(2)) {
        uint8_t answer = receive(f);
        if (answer) answers.push_back({f, answer});
      }
    }
  }
  void write(uint16_t v) {
    report = v;
    ASSERT_TRUE(device.write(report, writeDone, writeFailed));
    settle();
  }
};

// A write to the hub, 128 mission updates, then another write of the same hub channel: the second
// must reach the hub's accept handler, not be taken for a retry of the first.
TEST_F(WrapCases, AWriteAfter128UpdatesIsNotTakenForTheWriteBefore) {
  write(++token);
  for (int i = 0; i < 128; ++i) {
    device.progress(job, ++token);
    settle();
  }
  write(++token);
  EXPECT_EQ(writesDone, 2);
  EXPECT_EQ(hub.delivered['c'], 2);
  expectExact();
}

// A progress update, exactly 128 writes to the hub, then the final: the final must reach the hub.
TEST_F(WrapCases, AFinalAfter128WritesIsNotTakenForTheProgressBefore) {
  device.progress(job, ++token);
  settle();
  for (int i = 0; i < 128; ++i) write(++token);
  device.finish(job, ++token);
  settle();
  EXPECT_EQ(hub.delivered['m'], 2);
  EXPECT_EQ(hub.delivered['c'], 128);
  expectExact();
}

// An event, 255 other messages of the device, then the next event: 256 apart on one counter.
TEST_F(WrapCases, AnEventAfter255OtherMessagesIsNotTakenForTheEventBefore) {
  device.emit(note, ++token);
  settle();
  for (int i = 0; i < 255; ++i) {
    device.progress(job, ++token);
    settle();
  }
  device.emit(note, ++token);
  settle();
  EXPECT_EQ(hub.delivered['e'], 2);
  expectExact();
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
