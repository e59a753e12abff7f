// Missions on the device (session/missions.h, docs/PROTOCOL.md 11) against a fake stream and clock:
// the descriptor entry, start exactly once, BUSY, REJECTED, malformed ops, cancel, the R state, and
// the M updates: latest progress wins, finals never lost and last, stop and wait with retries, a NAK
// ending an update, updates kept across link loss.
#include "fixture.h"

using namespace hubwire;
using namespace hubwire::test;

// The sketch under test (file scope, as in a sketch).
Mission<float(float), float> drive;  // id 1
Mission<void(), void> home;          // id 2
Event<uint8_t> bumper;               // id 3
uint8_t level;                       // id 4
int starts, cancels, homeStarts, homeCancels;
float goalSeen;
bool refuse, reportInStart;
Session* sketch;  // the session the sketch's callbacks report to

bool startDrive(float metres) {
  ++starts;
  goalSeen = metres;
  if (reportInStart) sketch->progress(drive, 0.25f);
  return !refuse;
}
void cancelDrive() { ++cancels; }
void startHome() { ++homeStarts; }
void cancelHome() {  // ends the run itself: the hub gets this result, not "cancelled"
  ++homeCancels;
  sketch->finish(home);
}

HUBWIRE_CHANNELS(rover, "rover",
  mission("drive", drive, startDrive, cancelDrive).range(0.0f, 10.0f).unit("m").progressMax(2.5f),
  mission("home", home, startHome, cancelHome),
  event("bumper", bumper),
  expose("level", level).writable());

namespace {

const uint8_t kDrive = 1, kHome = 2, kBumper = 3;

class MissionTest : public MissionHub {
 protected:
  void SetUp() override {
    MissionHub::SetUp();
    drive = decltype(drive)();
    home = decltype(home)();
    starts = cancels = homeStarts = homeCancels = 0;
    goalSeen = 0;
    refuse = reportInStart = false;
    sketch = &device;
    ASSERT_TRUE(device.begin(rover, 1));
    link();
  }
  // Starts drive and returns its run number.
  uint8_t started(float goal = 2.0f) {
    RxFrame a = start(kDrive, le(goal));
    EXPECT_EQ(a.type, kMsgResponse);
    EXPECT_EQ(a.payload.size(), 1u);
    return a.payload.empty() ? 0 : a.payload[0];
  }
};

TEST(MissionDescriptor, TheEntryNamesGoalResultAndProgress) {
  std::string json(rover.json, rover.jsonLength);
  EXPECT_NE(json.find("{\"id\":1,\"n\":\"drive\",\"a\":\"m\",\"t\":\"f32\",\"rt\":\"f32\",\"pt\":\"f32\",\"pmax\":2.5,"
                      "\"u\":\"m\",\"min\":0,\"max\":10}"),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("{\"id\":2,\"n\":\"home\",\"a\":\"m\",\"t\":\"void\"}"), std::string::npos) << json;
}

TEST_F(MissionTest, StartAnswersTheRunAndARetryStartsNothing) {
  RxFrame a = start(kDrive, le(1.5f));
  EXPECT_EQ(a.type, kMsgResponse);
  EXPECT_EQ(a.payload, Bytes{1});
  EXPECT_EQ(starts, 1);
  EXPECT_EQ(goalSeen, 1.5f);
  EXPECT_TRUE(drive.running());
  EXPECT_EQ(drive.run(), 1);
  RxFrame again = ask(kMsgControl, hubSeq, kDrive, Bytes{kMissionStart, 0, 0, 0x40, 0x40});  // same seq and id
  EXPECT_EQ(again.type, kMsgResponse);
  EXPECT_EQ(again.payload, Bytes{1});
  EXPECT_EQ(starts, 1);
  EXPECT_EQ(goalSeen, 1.5f);
}

TEST_F(MissionTest, AStartWhileRunningIsBusy) {
  started();
  RxFrame a = start(kDrive, le(1.0f));
  EXPECT_EQ(a.type, kMsgNak);
  EXPECT_EQ(a.payload, nak(kErrBusy));
  EXPECT_EQ(starts, 1);
  EXPECT_EQ(drive.run(), 1);
}

TEST_F(MissionTest, ARefusedStartIsRejectedAndLeavesNoRun) {
  refuse = reportInStart = true;
  RxFrame a = start(kDrive, le(1.0f));
  EXPECT_EQ(a.type, kMsgNak);
  EXPECT_EQ(a.payload, nak(kErrRejected));
  EXPECT_FALSE(drive.running());
  EXPECT_EQ(state(kDrive).payload, (Bytes{0, 0}));
  EXPECT_TRUE(only(step(HUBWIRE_EVENT_RETRY_MS), kMsgMission).empty());  // its progress went with it
  refuse = false;
  EXPECT_EQ(started(), 1);
}

TEST_F(MissionTest, MalformedStartsAndOpsAreRefusedInOrder) {
  EXPECT_EQ(control(kDrive, Bytes{}).payload, nak(kErrBadLength));
  EXPECT_EQ(control(kDrive, Bytes{3}).payload, nak(kErrBadValue));
  EXPECT_EQ(control(kDrive, Bytes{0, 1}).payload, nak(kErrBadValue));
  EXPECT_EQ(control(kDrive, Bytes{kMissionCancel}).payload, nak(kErrBadLength));
  EXPECT_EQ(control(kDrive, Bytes{kMissionCancel, 1, 0}).payload, nak(kErrBadLength));
  EXPECT_EQ(start(kDrive, Bytes{0, 0}).payload, nak(kErrBadLength));
  EXPECT_EQ(start(kDrive, le(10.5f)).payload, nak(kErrOutOfRange));
  EXPECT_EQ(start(kDrive, le(-0.5f)).payload, nak(kErrOutOfRange));
  EXPECT_EQ(start(kHome, Bytes{1}).payload, nak(kErrBadLength));
  EXPECT_EQ(ask(kMsgRequest, ++hubSeq, kDrive, Bytes{1}).payload, nak(kErrBadLength));
  EXPECT_EQ(starts, 0);
  EXPECT_EQ(homeStarts, 0);
  EXPECT_EQ(ask(kMsgControl, ++hubSeq, kBumper, Bytes{kMissionStart}).payload, nak(kErrNotWritable));
}

TEST_F(MissionTest, CancelOfTheRunningRunCallsCancelOnceAndEndsItCancelled) {
  uint8_t run = started();
  RxFrame a = cancel(kDrive, run);
  EXPECT_EQ(a.type, kMsgResponse);
  EXPECT_EQ(a.payload, Bytes{1});
  EXPECT_EQ(cancels, 1);
  EXPECT_FALSE(drive.running());
  auto m = only(others, kMsgMission);  // sent in the same update, after the answer
  RxFrame again = ask(kMsgControl, hubSeq, kDrive, Bytes{kMissionCancel, run});  // a retry
  EXPECT_EQ(again.payload, Bytes{1});
  EXPECT_EQ(cancels, 1);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].id, kDrive);
  EXPECT_EQ(m[0].payload, update(run, kMissionCancelled));
  EXPECT_EQ(cancel(kDrive, run).payload, Bytes{0});  // ended: not running
  EXPECT_EQ(cancels, 1);
}

TEST_F(MissionTest, CancelOfARunNotRunningAnswersZero) {
  EXPECT_EQ(cancel(kDrive, 1).payload, Bytes{0});  // never started
  uint8_t run = started();
  EXPECT_EQ(cancel(kDrive, (uint8_t)(run + 1)).payload, Bytes{0});  // another run
  EXPECT_EQ(cancels, 0);
  EXPECT_TRUE(drive.running());
}

TEST_F(MissionTest, ACancelTheSketchAnswersWithAResultEndsWithThatResult) {
  RxFrame a = start(kHome);
  ASSERT_EQ(a.payload, Bytes{1});
  EXPECT_EQ(homeStarts, 1);
  EXPECT_EQ(cancel(kHome, 1).payload, Bytes{1});
  EXPECT_EQ(homeCancels, 1);
  auto m = only(others, kMsgMission);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].payload, update(1, kMissionSucceeded));
}

TEST_F(MissionTest, StateIsTheLatestRunAndWhetherItRuns) {
  EXPECT_EQ(state(kDrive).payload, (Bytes{0, 0}));
  uint8_t run = started();
  RxFrame s = state(kDrive);
  EXPECT_EQ(s.type, kMsgResponse);
  EXPECT_EQ(s.payload, (Bytes{run, 1}));
  ASSERT_TRUE(device.finish(drive, 2.0f));
  EXPECT_EQ(state(kDrive).payload, (Bytes{run, 1}));  // its final not sent yet
  step();                                              // sent now
  EXPECT_EQ(state(kDrive).payload, (Bytes{run, 0}));
}

TEST_F(MissionTest, RunNumbersCountAcceptedStartsAndWrapTo1) {
  EXPECT_EQ(started(), 1);
  device.finish(drive, 1.0f);
  ack(only(step(), kMsgMission).at(0));
  refuse = true;
  start(kDrive, le(1.0f));  // refused: not counted
  refuse = false;
  EXPECT_EQ(started(), 2);
  device.finish(drive, 1.0f);
  ack(only(step(), kMsgMission).at(0));
  drive.run_ = 255;
  EXPECT_EQ(started(), 1);
}

TEST_F(MissionTest, OnlyTheLatestProgressNotYetSentIsSent) {
  uint8_t run = started();
  ASSERT_TRUE(device.progress(drive, 0.5f));
  auto m = only(step(), kMsgMission);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].payload, update(run, kMissionProgress, 0.5f));
  ASSERT_TRUE(device.progress(drive, 1.0f));
  ASSERT_TRUE(device.progress(drive, 1.5f));
  EXPECT_TRUE(only(step(), kMsgMission).empty());  // one update unacked at a time
  ack(m[0]);
  auto m2 = only(step(), kMsgMission);
  ASSERT_EQ(m2.size(), 1u);
  EXPECT_EQ(m2[0].payload, update(run, kMissionProgress, 1.5f));
  EXPECT_NE(m2[0].seq, m[0].seq);
  ack(m2[0]);
  EXPECT_TRUE(only(step(HUBWIRE_EVENT_RETRY_MS), kMsgMission).empty());
}

TEST_F(MissionTest, AFinalTakesThePlaceOfAProgressNotYetSent) {
  uint8_t run = started();
  device.progress(drive, 1.0f);
  ASSERT_TRUE(device.finish(drive, 2.0f));
  auto m = only(step(), kMsgMission);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].payload, update(run, kMissionSucceeded, 2.0f));
  ack(m[0]);
  EXPECT_TRUE(only(step(HUBWIRE_EVENT_RETRY_MS), kMsgMission).empty());
}

TEST_F(MissionTest, ProgressSentGoesBeforeTheFinalAndNothingFollowsIt) {
  uint8_t run = started();
  device.progress(drive, 1.0f);
  auto p = only(step(), kMsgMission);
  ASSERT_EQ(p.size(), 1u);
  ASSERT_TRUE(device.fail(drive, 7));
  EXPECT_FALSE(device.progress(drive, 1.5f));
  EXPECT_FALSE(device.finish(drive, 2.0f));
  EXPECT_FALSE(device.fail(drive, 8));
  ack(p[0]);
  auto f = only(step(), kMsgMission);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].payload, (Bytes{run, kMissionFailed, 7}));
  ack(f[0]);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(only(step(HUBWIRE_EVENT_RETRY_MS), kMsgMission).empty()) << i;
}

TEST_F(MissionTest, AnUpdateIsRetriedWithItsSeqUntilAcked) {
  uint8_t run = started();
  device.progress(drive, 0.5f);
  auto m = only(step(), kMsgMission);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_TRUE(only(step(HUBWIRE_EVENT_RETRY_MS - 1), kMsgMission).empty());
  device.progress(drive, 0.75f);  // waits: the retry carries what was sent
  for (int i = 0; i < 3; ++i) {
    auto r = only(step(i == 0 ? 1 : HUBWIRE_EVENT_RETRY_MS), kMsgMission);
    ASSERT_EQ(r.size(), 1u) << i;
    EXPECT_EQ(r[0].seq, m[0].seq);
    EXPECT_EQ(r[0].payload, update(run, kMissionProgress, 0.5f));
    sendFrame(stream, kMsgHeartbeat, 0, 0, Bytes(kHeartbeatSize, 0));  // keeps the link
  }
  ack(m[0]);
  auto next = only(step(), kMsgMission);
  ASSERT_EQ(next.size(), 1u);
  EXPECT_EQ(next[0].payload, update(run, kMissionProgress, 0.75f));
}

TEST_F(MissionTest, ANakEndsAnUpdateLikeAnAck) {
  uint8_t run = started();
  device.finish(drive, 3.0f);
  auto m = only(step(), kMsgMission);
  ASSERT_EQ(m.size(), 1u);
  ack(m[0], kMsgNak);
  EXPECT_TRUE(only(step(HUBWIRE_EVENT_RETRY_MS), kMsgMission).empty());
  EXPECT_EQ(started(), (uint8_t)(run + 1));
}

TEST_F(MissionTest, AnAnswerForAnotherSeqOrIdDoesNotEndTheUpdate) {
  started();
  device.progress(drive, 0.5f);
  auto m = only(step(), kMsgMission);
  ASSERT_EQ(m.size(), 1u);
  sendFrame(stream, kMsgAck, (uint8_t)(m[0].seq + 1), kDrive);
  sendFrame(stream, kMsgAck, m[0].seq, kHome);
  auto r = only(step(HUBWIRE_EVENT_RETRY_MS), kMsgMission);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].seq, m[0].seq);
}

TEST_F(MissionTest, UpdatesWaitForTheLinkAndTheOneInFlightGoesAgainAtOnce) {
  uint8_t run = started();
  device.progress(drive, 0.5f);
  auto m = only(step(), kMsgMission);
  ASSERT_EQ(m.size(), 1u);
  step(HUBWIRE_HEARTBEAT_MS * HUBWIRE_LOST_AFTER_BEATS);  // the hub went silent
  ASSERT_FALSE(device.linked());
  EXPECT_TRUE(drive.running());  // the run goes on: the sketch decides
  device.progress(drive, 1.0f);
  device.finish(drive, 2.0f);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(only(step(HUBWIRE_EVENT_RETRY_MS), kMsgMission).empty()) << i;
  sendFrame(stream, kMsgHello, 0, 0, hubHello(7));
  auto again = only(step(), kMsgMission);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].seq, m[0].seq);
  EXPECT_EQ(again[0].payload, update(run, kMissionProgress, 0.5f));
  ack(again[0]);
  auto fin = only(step(), kMsgMission);
  ASSERT_EQ(fin.size(), 1u);
  EXPECT_EQ(fin[0].payload, update(run, kMissionSucceeded, 2.0f));
}

TEST_F(MissionTest, ANewHubSessionGetsTheUpdatesOfARunAlreadyGoing) {
  uint8_t run = started();
  sendFrame(stream, kMsgHello, 0, 0, hubHello(99));  // another hub, no link loss in between
  step();
  device.finish(drive, 2.0f);
  auto m = only(step(), kMsgMission);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].payload, update(run, kMissionSucceeded, 2.0f));
}

TEST_F(MissionTest, AStartWaitsUntilTheLastRunsFinalIsSent) {
  // The hub has not seen the run end until its final is sent: a start is BUSY until then.
  uint8_t run = started();
  step(HUBWIRE_HEARTBEAT_MS * HUBWIRE_LOST_AFTER_BEATS);
  device.finish(drive, 2.0f);
  link();
  // The hello brought the link up and, in the same update, the final went out.
  EXPECT_EQ(start(kDrive, le(1.0f)).type, kMsgResponse);
  EXPECT_EQ(drive.run(), (uint8_t)(run + 1));
}

TEST_F(MissionTest, AStartWhileTheFinalIsUnsentIsBusy) {
  started();
  device.progress(drive, 0.5f);
  auto p = only(step(), kMsgMission);  // in flight, unacked
  ASSERT_EQ(p.size(), 1u);
  device.finish(drive, 2.0f);  // waits behind it
  EXPECT_EQ(state(kDrive).payload[1], 1);  // still running for the hub: R agrees with BUSY
  EXPECT_EQ(start(kDrive, le(1.0f)).payload, nak(kErrBusy));
  ack(p[0]);
  auto f = only(step(), kMsgMission);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(start(kDrive, le(1.0f)).type, kMsgResponse);  // the final sent (not yet acked)
  EXPECT_EQ(starts, 2);
}

TEST_F(MissionTest, StateSaysRunningUntilTheFinalIsSent) {
  started();
  device.progress(drive, 0.5f);
  auto p = only(step(), kMsgMission);
  ASSERT_EQ(p.size(), 1u);
  device.finish(drive, 2.0f);
  EXPECT_EQ(state(kDrive).payload[1], 1);
  ack(p[0]);
  ASSERT_EQ(only(step(), kMsgMission).size(), 1u);  // the final goes out
  EXPECT_EQ(state(kDrive).payload[1], 0);
}

TEST_F(MissionTest, TwoMissionsTakeTurnsOneUpdateInFlight) {
  uint8_t d = started();
  ASSERT_EQ(start(kHome).type, kMsgResponse);
  device.progress(drive, 0.5f);
  device.progress(home);
  auto a = only(step(), kMsgMission);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_TRUE(only(step(), kMsgMission).empty());
  ack(a[0]);
  auto b = only(step(), kMsgMission);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_NE(a[0].id, b[0].id);
  device.progress(drive, 1.0f);
  device.progress(home);
  ack(b[0]);
  auto c = only(step(), kMsgMission);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].id, a[0].id);  // round robin: the one that waited longest goes first
  EXPECT_EQ(a[0].id == kDrive ? a[0].payload : b[0].payload, update(d, kMissionProgress, 0.5f));
}

TEST_F(MissionTest, ProgressReportedInsideStartFollowsTheAnswer) {
  reportInStart = true;
  RxFrame a = start(kDrive, le(1.0f));
  ASSERT_EQ(a.payload, Bytes{1});
  auto m = only(others, kMsgMission);  // the same update() as the answer, after it
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].payload, update(1, kMissionProgress, 0.25f));
}

TEST_F(MissionTest, NothingIsSentBeforeTheHubStartsARun) {
  EXPECT_FALSE(device.progress(drive, 0.5f));
  EXPECT_FALSE(device.finish(drive, 1.0f));
  EXPECT_FALSE(device.fail(drive, 1));
  EXPECT_FALSE(drive.running());
  EXPECT_TRUE(only(step(HUBWIRE_EVENT_RETRY_MS), kMsgMission).empty());
}

}  // namespace
