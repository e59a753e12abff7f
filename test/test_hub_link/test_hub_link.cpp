// The device's side of both directions (docs/PROTOCOL.md 10) against a fake stream and clock: the
// "hub" descriptor key, the bind report, requests, writes and calls retried with one seq and
// answered once, timeouts, a full queue, hub events delivered once and in order, the hub
// descriptor read in chunks, the hub's health, and the golden vectors of test/vectors/both.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "fakes.h"
#include "frames.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"
#include "hubwire/wire/bytes.h"

using namespace hubwire;
using namespace hubwire::test;

// The sketch under test (file scope, as in a sketch; the one table with hub channels).
float temp = 19.5f;
float setpoint;
uint16_t report = 1234;
RemoteAction<bool(float)> dock;
uint8_t mode;
int doneCalls, failCalls, modeCalls, dockedTrue;
uint8_t lastFail;
void done() { ++doneCalls; }
void fail(uint8_t code) {
  ++failCalls;
  lastFail = code;
}
void docked(bool ok) { dockedTrue += ok; }
void modeChanged() { ++modeCalls; }
int heatCalls;
void setHeat(bool) { ++heatCalls; }
Event<uint8_t> overheat;
std::string chunkText;
uint16_t chunkTotal;
void gotChunk(uint16_t offset, uint16_t total, const uint8_t* data, uint8_t n) {
  if (offset == chunkText.size()) chunkText.append((const char*)data, n);
  chunkTotal = total;
}

HUBWIRE_CHANNELS(thermo, "thermo",
  expose("temp", temp),
  control("heat", setHeat),
  event("overheat", overheat),
  remote("setpoint", setpoint).unit("C"),       // hub id 1
  remote("report", report).writeOnly(),         // hub id 2
  remoteAction("dock", dock),                   // hub id 3
  remoteEvent("mode", mode).onChange(modeChanged));  // hub id 4

uint8_t plainLevel;
HUBWIRE_CHANNELS(plain, "plain", expose("level", plainLevel));  // no hub channels

namespace {

const char kExpected[] =
    "{\"p\":1,\"n\":\"thermo\",\"ch\":[{\"id\":1,\"n\":\"temp\",\"a\":\"r\",\"t\":\"f32\"},"
    "{\"id\":2,\"n\":\"heat\",\"a\":\"w\",\"t\":\"bool\"},{\"id\":3,\"n\":\"overheat\",\"a\":\"e\",\"t\":\"u8\"}],\"hub\":["
    "{\"id\":1,\"n\":\"setpoint\",\"a\":\"r\",\"t\":\"f32\",\"u\":\"C\"},{\"id\":2,\"n\":\"report\",\"a\":\"w\",\"t\":\"u16\"},"
    "{\"id\":3,\"n\":\"dock\",\"a\":\"c\",\"t\":\"f32\",\"rt\":\"bool\"},{\"id\":4,\"n\":\"mode\",\"a\":\"e\",\"t\":\"u8\"}]}";

class HubLinkTest : public ::testing::Test {
 protected:
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  Session device{port};
  uint8_t hubSeq = 0x40;

  void SetUp() override {
    doneCalls = failCalls = modeCalls = dockedTrue = heatCalls = 0;
    lastFail = 0;
    chunkText.clear();
    hubLink.owner = nullptr;  // each test's session is new, though at the same address
    ASSERT_TRUE(device.begin(thermo, 1));
  }
  std::vector<RxFrame> leftover;  // what the device sent besides the answer bind() looked for
  std::vector<RxFrame> step(uint32_t ms = 0) {
    clock.now += ms;
    device.update();
    std::vector<RxFrame> out;
    out.swap(leftover);
    for (auto& f : drain(stream)) out.push_back(f);
    return out;
  }
  void link(uint32_t nonce = 7) {
    sendFrame(stream, kMsgHello, 0, 0, hubHello(nonce));
    step();
  }
  // The hub's bind report; returns the device's answer.
  RxFrame bind(const Bytes& status) {
    Bytes p{1};
    p.insert(p.end(), status.begin(), status.end());
    sendFrame(stream, kMsgControl, ++hubSeq, 0, p);
    auto out = step();
    RxFrame answer{0, 0, 0, {}};
    for (auto& f : out) {
      if (answer.type == 0 && (f.type == kMsgAck || f.type == kMsgNak) && f.id == 0) answer = f;
      else leftover.push_back(f);
    }
    return answer;
  }
  // Frames of the given type the device sent.
  static std::vector<RxFrame> only(const std::vector<RxFrame>& fs, uint8_t type) {
    std::vector<RxFrame> r;
    for (auto& f : fs)
      if (f.type == type) r.push_back(f);
    return r;
  }
};

TEST(HubDescriptor, ListsTheHubChannelsAfterTheDevicesOwn) {
  EXPECT_EQ(std::string(thermo.json, thermo.jsonLength), kExpected);
  EXPECT_EQ(thermo.count, 3);  // hub channels are not device channels
}

TEST_F(HubLinkTest, NothingIsSentBeforeTheBindReport) {
  link();
  ASSERT_TRUE(device.request(setpoint, done, fail));
  EXPECT_TRUE(device.hubBinding().pending());
  EXPECT_TRUE(only(step(50), kMsgRequest).empty());
  RxFrame ack = bind({0, 0, 0, 0});
  EXPECT_EQ(ack.type, kMsgAck);
  EXPECT_TRUE(device.hubBinding().ok());
  auto r = only(step(), kMsgRequest);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].id, 1);
  EXPECT_TRUE(r[0].payload.empty());
}

TEST_F(HubLinkTest, BindReportNamesTheFirstFailureAndIsCheckedForLength) {
  link();
  EXPECT_EQ(bind({0, 0}).type, kMsgNak);  // 1 + N bytes or nothing
  EXPECT_TRUE(device.hubBinding().pending());
  EXPECT_EQ(bind({0, 2, 3, 0}).type, kMsgAck);
  BindStatus b = device.hubBinding();
  EXPECT_EQ(b.state, kBindFailed);
  EXPECT_EQ(b.index, 2);
  EXPECT_EQ(b.code, kErrUnknownChannel);
  link(8);  // a new hub session: pending until its own report
  EXPECT_TRUE(device.hubBinding().pending());
}

TEST_F(HubLinkTest, RequestLandsInTheVariable) {
  link();
  bind({0, 0, 0, 0});
  device.request(setpoint, done, fail);
  auto r = only(step(), kMsgRequest);
  ASSERT_EQ(r.size(), 1u);
  sendFrame(stream, kMsgResponse, r[0].seq, 1, le(21.5f));
  step();
  EXPECT_EQ(setpoint, 21.5f);
  EXPECT_EQ(doneCalls, 1);
  EXPECT_EQ(device.hubQueued(), 0);
}

TEST_F(HubLinkTest, WriteIsRetriedWithOneSeqAndAnsweredOnce) {
  link();
  bind({0, 0, 0, 0});
  report = 1234;
  ASSERT_TRUE(device.write(report, done, fail));
  report = 9;  // the value was taken when queued
  auto first = only(step(), kMsgControl);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].payload, le<uint16_t>(1234));
  EXPECT_TRUE(only(step(HUBWIRE_HUB_RETRY_MS - 1), kMsgControl).empty());
  auto retry = only(step(1), kMsgControl);
  ASSERT_EQ(retry.size(), 1u);
  EXPECT_EQ(retry[0].seq, first[0].seq);
  EXPECT_EQ(retry[0].payload, first[0].payload);
  sendFrame(stream, kMsgAck, first[0].seq, 2);
  sendFrame(stream, kMsgAck, first[0].seq, 2);  // the answer to the retry too
  step();
  EXPECT_EQ(doneCalls, 1);
  EXPECT_EQ(failCalls, 0);
  EXPECT_TRUE(only(step(HUBWIRE_HUB_RETRY_MS * 2), kMsgControl).empty());
}

TEST_F(HubLinkTest, NakIsReportedWithItsCode) {
  link();
  bind({0, 0, 0, 0});
  device.write(report, done, fail);
  auto c = only(step(), kMsgControl);
  sendFrame(stream, kMsgNak, c[0].seq, 2, Bytes{kErrOutOfRange});
  step();
  EXPECT_EQ(failCalls, 1);
  EXPECT_EQ(lastFail, kErrOutOfRange);
  EXPECT_EQ(doneCalls, 0);
}

TEST_F(HubLinkTest, TimeoutAfterTheConfiguredTries) {
  link();
  bind({0, 0, 0, 0});
  device.write(report, done, fail);
  size_t sent = 0;
  for (int i = 0; i < HUBWIRE_HUB_TRIES + 2; ++i) {
    sent += only(step(HUBWIRE_HUB_RETRY_MS), kMsgControl).size();
    sendFrame(stream, kMsgHeartbeat, 1, 0, Bytes(10, 0));  // keep the link up
  }
  EXPECT_EQ(sent, (size_t)HUBWIRE_HUB_TRIES);
  EXPECT_EQ(failCalls, 1);
  EXPECT_EQ(lastFail, kHubTimeout);
}

TEST_F(HubLinkTest, WithoutABindReportRequestsTimeOutFromWhenTheyWereQueued) {
  link();  // an old hub never binds
  device.request(setpoint, done, fail);
  step(HUBWIRE_HUB_RETRY_MS * HUBWIRE_HUB_TRIES - 1);
  EXPECT_EQ(failCalls, 0);
  step(1);
  EXPECT_EQ(failCalls, 1);
  EXPECT_EQ(lastFail, kHubTimeout);
}

TEST_F(HubLinkTest, FullQueueIsRefused) {
  for (int i = 0; i < HUBWIRE_HUB_QUEUE; ++i) EXPECT_TRUE(device.request(setpoint));
  EXPECT_FALSE(device.request(setpoint));
  EXPECT_EQ(device.hubQueued(), HUBWIRE_HUB_QUEUE);
  EXPECT_FALSE(device.request(temp));    // not a hub channel
  EXPECT_FALSE(device.write(setpoint));  // declared read-only
}

TEST_F(HubLinkTest, CallDeliversTheReturnValue) {
  link();
  bind({0, 0, 0, 0});
  ASSERT_TRUE(device.call(dock, 0.25f, docked, fail));
  auto c = only(step(), kMsgControl);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].id, 3);
  EXPECT_EQ(c[0].payload, le(0.25f));
  sendFrame(stream, kMsgResponse, c[0].seq, 3, Bytes{1});
  step();
  EXPECT_EQ(dockedTrue, 1);
}

TEST_F(HubLinkTest, HubEventsOnceAndInOrder) {
  link();
  bind({0, 0, 0, 0});
  sendFrame(stream, kMsgEvent, 0x51, 4, Bytes{2});
  auto a = step();
  ASSERT_EQ(a.size() >= 1, true);
  EXPECT_EQ(only(a, kMsgAck).size(), 1u);
  EXPECT_EQ(mode, 2);
  EXPECT_EQ(modeCalls, 1);
  mode = 0;
  sendFrame(stream, kMsgEvent, 0x51, 4, Bytes{2});  // a retry: acked again, not delivered
  EXPECT_EQ(only(step(), kMsgAck).size(), 1u);
  EXPECT_EQ(mode, 0);
  EXPECT_EQ(modeCalls, 1);
  sendFrame(stream, kMsgEvent, 0x52, 4, Bytes{3});
  step();
  EXPECT_EQ(mode, 3);
  EXPECT_EQ(modeCalls, 2);
  sendFrame(stream, kMsgEvent, 0x53, 1, Bytes{3});  // hub id 1 takes no events
  auto n = only(step(), kMsgNak);
  ASSERT_EQ(n.size(), 1u);
  EXPECT_EQ(n[0].payload, Bytes{kErrUnknownChannel});
  sendFrame(stream, kMsgEvent, 0x54, 4, Bytes{3, 3});
  n = only(step(), kMsgNak);
  ASSERT_EQ(n.size(), 1u);
  EXPECT_EQ(n[0].payload, Bytes{kErrBadLength});
  link(9);  // a new hub numbers afresh: the same seq is a new event
  sendFrame(stream, kMsgEvent, 0x52, 4, Bytes{4});
  step();
  EXPECT_EQ(mode, 4);
  EXPECT_EQ(modeCalls, 3);
}

TEST_F(HubLinkTest, EventsAndRequestsShareOneCounter) {
  link();
  bind({0, 0, 0, 0});
  ASSERT_TRUE(device.emit(overheat, 1));
  device.request(setpoint);
  auto out = step();
  auto e = only(out, kMsgEvent);
  auto r = only(out, kMsgRequest);
  ASSERT_EQ(e.size(), 1u);
  ASSERT_EQ(r.size(), 1u);
  // one counter: never the same seq outstanding (the request is numbered first in an update)
  EXPECT_EQ(e[0].seq, (uint8_t)(r[0].seq + 1));
  sendFrame(stream, kMsgAck, e[0].seq, e[0].id);
  sendFrame(stream, kMsgResponse, r[0].seq, 1, le(1.0f));
  step();
  EXPECT_EQ(device.eventsQueued(), 0);
  EXPECT_EQ(doneCalls, 0);
  ASSERT_TRUE(device.emit(overheat, 2));
  auto e2 = only(step(), kMsgEvent);
  ASSERT_EQ(e2.size(), 1u);
  EXPECT_EQ(e2[0].seq, (uint8_t)(e[0].seq + 1));
  // A retried event keeps its seq while requests go on.
  device.request(setpoint);
  auto out2 = step(HUBWIRE_EVENT_RETRY_MS);
  auto e3 = only(out2, kMsgEvent);
  ASSERT_EQ(e3.size(), 1u);
  EXPECT_EQ(e3[0].seq, e2[0].seq);
  ASSERT_EQ(only(out2, kMsgRequest).size(), 1u);
  EXPECT_EQ(only(out2, kMsgRequest)[0].seq, (uint8_t)(e2[0].seq + 1));
}

// An event acked in the update after it went, before the link's next look at the queue: the next
// events and requests must still take seqs of their own (a repeated event seq is a duplicate to
// the hub, which drops the event).
TEST_F(HubLinkTest, EventsAckedAtOnceNeverRepeatASeq) {
  link();
  bind({0, 0, 0, 0});
  std::vector<uint8_t> seqs;
  for (uint8_t v = 1; v <= 3; ++v) ASSERT_TRUE(device.emit(overheat, v));
  for (int i = 0; i < 3; ++i) {
    auto e = only(step(), kMsgEvent);
    ASSERT_EQ(e.size(), 1u) << i;
    seqs.push_back(e[0].seq);
    if (i == 1) step();  // the link sees this one in flight before its ACK
    sendFrame(stream, kMsgAck, e[0].seq, e[0].id);
  }
  step();
  device.request(setpoint);
  auto r = only(step(), kMsgRequest);
  ASSERT_EQ(r.size(), 1u);
  seqs.push_back(r[0].seq);
  ASSERT_TRUE(device.emit(overheat, 4));
  auto e4 = only(step(), kMsgEvent);
  ASSERT_EQ(e4.size(), 1u);
  seqs.push_back(e4[0].seq);
  for (size_t i = 1; i < seqs.size(); ++i) EXPECT_EQ(seqs[i], (uint8_t)(seqs[i - 1] + 1)) << i;
}

TEST_F(HubLinkTest, ARetriedBindReportIsAnsweredAgainNotApplied) {
  link();
  sendFrame(stream, kMsgControl, 0x30, 0, Bytes{1, 0, 2, 0, 0});
  EXPECT_EQ(only(step(), kMsgAck).size(), 1u);
  EXPECT_EQ(device.hubBinding().index, 2);
  sendFrame(stream, kMsgControl, 0x30, 0, Bytes{1, 0, 0, 0, 0});  // same seq and id: a retry
  EXPECT_EQ(only(step(), kMsgAck).size(), 1u);
  EXPECT_EQ(device.hubBinding().state, kBindFailed);  // not applied again
  sendFrame(stream, kMsgControl, 0x31, 0, Bytes{1, 0, 0, 0, 0});  // a new report
  step();
  EXPECT_TRUE(device.hubBinding().ok());
}

// A hub control whose ACK was lost is retried; a chunk of the hub's descriptor arriving in between
// (the answer to the device's own J) must not make the device apply the control twice.
TEST_F(HubLinkTest, AHubChunkBetweenAControlAndItsRetryKeepsItExactlyOnce) {
  link();
  bind({0, 0, 0, 0});
  ASSERT_TRUE(device.readHubDescriptor(0, gotChunk, fail));
  auto j = only(step(), kMsgChunk);
  ASSERT_EQ(j.size(), 1u);
  sendFrame(stream, kMsgControl, 0x60, 2, Bytes{1});  // heat on
  EXPECT_EQ(only(step(), kMsgAck).size(), 1u);
  EXPECT_EQ(heatCalls, 1);
  Bytes chunk{0, 0, 2, 0, '{', '}'};
  sendFrame(stream, kMsgChunk, j[0].seq, 0, chunk);
  step();
  EXPECT_EQ(chunkText, "{}");
  sendFrame(stream, kMsgControl, 0x60, 2, Bytes{1});  // the hub's retry: its ACK was lost
  EXPECT_EQ(only(step(), kMsgAck).size(), 1u);
  EXPECT_EQ(heatCalls, 1);
}

// A hub read ends the window of the control before it (PROTOCOL.md 4.1); an answer to the device's
// own chunk request afterwards is no hub transaction and must not open that window again.
TEST_F(HubLinkTest, AChunkAnswerAfterAHubReadDoesNotReviveTheControlBeforeIt) {
  link();
  bind({0, 0, 0, 0});
  ASSERT_TRUE(device.readHubDescriptor(0, gotChunk, fail));
  auto j = only(step(), kMsgChunk);
  ASSERT_EQ(j.size(), 1u);
  sendFrame(stream, kMsgControl, 0x61, 2, Bytes{1});  // heat on
  EXPECT_EQ(only(step(), kMsgAck).size(), 1u);
  sendFrame(stream, kMsgRequest, 0x62, 1);  // a read: the control's window ends
  EXPECT_EQ(only(step(), kMsgResponse).size(), 1u);
  sendFrame(stream, kMsgChunk, j[0].seq, 0, Bytes{0, 0, 2, 0, '{', '}'});
  step();
  EXPECT_EQ(chunkText, "{}");
  sendFrame(stream, kMsgControl, 0x61, 2, Bytes{1});  // a new control that happens to take that seq
  EXPECT_EQ(only(step(), kMsgAck).size(), 1u);
  EXPECT_EQ(heatCalls, 2);
}

TEST_F(HubLinkTest, ReadsTheHubDescriptorInChunks) {
  const std::string hubJson = "{\"p\":1,\"n\":\"hub\",\"ch\":[{\"id\":1,\"n\":\"setpoint\",\"a\":\"r\",\"t\":\"f32\"}]}";
  link();
  bind({0, 0, 0, 0});
  while (chunkText.size() < hubJson.size()) {
    ASSERT_TRUE(device.readHubDescriptor((uint16_t)chunkText.size(), gotChunk, fail));
    auto j = only(step(), kMsgChunk);
    ASSERT_EQ(j.size(), 1u);
    uint16_t offset = loadU16(j[0].payload.data());
    uint8_t want = j[0].payload[2];
    EXPECT_EQ(want, HUBWIRE_MAX_PAYLOAD - kChunkHeader);
    size_t n = std::min<size_t>(want, hubJson.size() - offset);
    Bytes p(4);
    storeU16(&p[0], offset);
    storeU16(&p[2], (uint16_t)hubJson.size());
    p.insert(p.end(), hubJson.begin() + offset, hubJson.begin() + offset + n);
    sendFrame(stream, kMsgChunk, j[0].seq, 0, p);
    step();
  }
  EXPECT_EQ(chunkText, hubJson);
  EXPECT_EQ(chunkTotal, hubJson.size());
}

TEST_F(HubLinkTest, HubHealthFromItsHeartbeats) {
  Bytes hello = hubHello(7);
  storeU32(&hello[10], 0xA1B2C3D4);  // a hub that describes itself: ignored by the session
  storeU16(&hello[14], 321);
  sendFrame(stream, kMsgHello, 0, 0, hello);
  auto out = step();
  EXPECT_TRUE(device.linked());
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out[0].type, kMsgHello);
  Bytes beat(10);
  storeU16(&beat[0], 3);
  storeU16(&beat[2], 251);
  storeU16(&beat[4], 4);
  storeU16(&beat[6], 5);
  storeU16(&beat[8], 6);
  sendFrame(stream, kMsgHeartbeat, 3, 0, beat);
  step();
  const HubHealth& h = device.hubHealth();
  EXPECT_EQ(h.beats, 1);
  EXPECT_EQ(h.sinceMs, 251);
  EXPECT_EQ(h.crc, 4);
  EXPECT_EQ(h.overflow, 5);
  EXPECT_EQ(h.dropped, 6);
}

// The link is lost only after HUBWIRE_LOST_AFTER_BEATS silent heartbeats, longer than a request's
// tries last: a write in flight ends in a timeout, sent no more while the link is down.
TEST_F(HubLinkTest, AWriteInFlightWhenTheLinkDropsEndsInOneTimeout) {
  static_assert(250 * HUBWIRE_LOST_AFTER_BEATS >= HUBWIRE_HUB_RETRY_MS * HUBWIRE_HUB_TRIES, "defaults");
  link();
  bind({0, 0, 0, 0});
  device.write(report, done, fail);
  ASSERT_EQ(only(step(), kMsgControl).size(), 1u);
  size_t sent = 0;
  for (int t = 0; t < 250 * HUBWIRE_LOST_AFTER_BEATS; t += HUBWIRE_HUB_RETRY_MS)
    sent += only(step(HUBWIRE_HUB_RETRY_MS), kMsgControl).size();
  EXPECT_FALSE(device.linked());
  EXPECT_EQ(sent, (size_t)HUBWIRE_HUB_TRIES - 1);
  EXPECT_EQ(failCalls, 1);
  EXPECT_EQ(lastFail, kHubTimeout);
  link();
  EXPECT_TRUE(only(step(HUBWIRE_HUB_RETRY_MS), kMsgControl).empty());
  EXPECT_EQ(doneCalls + failCalls, 1);  // exactly one ending
}

// A session whose table declares no hub channel, in the same program, behaves as before: a bind
// report is an unknown channel, a hub event an unknown type, and it cannot request anything.
TEST(NoHubChannels, ASessionWithoutThemAnswersAsBefore) {
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  Session device{port};
  ASSERT_TRUE(device.begin(plain, 1));
  sendFrame(stream, kMsgHello, 0, 0, hubHello(3));
  device.update();
  drain(stream);
  sendFrame(stream, kMsgControl, 9, 0, Bytes{1, 0});
  sendFrame(stream, kMsgEvent, 10, 1, Bytes{1});
  device.update();
  auto out = drain(stream);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].type, kMsgNak);
  EXPECT_EQ(out[0].payload, Bytes{kErrUnknownChannel});
  EXPECT_EQ(out[1].type, kMsgNak);
  EXPECT_EQ(out[1].payload, Bytes{kErrUnknownType});
  EXPECT_FALSE(device.request(plainLevel));
}

// test/vectors/both/frames.json: every frame encodes to its wire bytes; the device's answers to the
// hub's frames are the ones the vectors give.
TEST(BothVectors, FramesEncodeAndTheDeviceAnswersAsGiven) {
  std::ifstream in(std::string(HUBWIRE_VECTORS_DIR) + "/both/frames.json");
  ASSERT_TRUE(in.good());
  nlohmann::json doc = nlohmann::json::parse(in);
  size_t n = 0;
  for (auto& v : doc["vectors"]) {
    Bytes payload = hex(v["payload"]);
    uint8_t out[300];
    size_t len = encodeFrame(v["type"], v["seq"], v["id"], payload.data(), (uint8_t)payload.size(), out);
    EXPECT_EQ(toHex(out, len), v["wire"].get<std::string>()) << v["name"];
    if (v["message"]["kind"] == "bind_report") {
      EXPECT_EQ(payload[0], 1);
      EXPECT_EQ(v["message"]["status"].size(), payload.size() - 1);
    }
    ++n;
  }
  EXPECT_GE(n, 20u);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
