// test/vectors/missions/frames.json (docs/PROTOCOL.md 11): every frame encodes to its wire bytes,
// the device's descriptor entries are the vectors', and the device plays each scenario: it answers
// the hub's frames with the frames given and, driven by the sketch's calls, sends the updates given.
#include <fstream>
#include <map>
#include <new>
#include <string>

#include <nlohmann/json.hpp>

#include "fixture.h"

using namespace hubwire;
using namespace hubwire::test;

// The vectors' device: drive at id 7, home at id 8 (six plain values before them).
uint8_t pad1, pad2, pad3, pad4, pad5, pad6;
Mission<float(float), float> vdrive;
Mission<void(), void> vhome;
int vStarts, vCancels;
bool vStartDrive(float goal) {
  ++vStarts;
  return goal != 3.0f;  // the vectors' sketch refuses 3.0
}
void vCancelDrive() { ++vCancels; }
void vStartHome() { ++vStarts; }
void vCancelHome() { ++vCancels; }
HUBWIRE_CHANNELS(vrover, "rover", expose("a", pad1), expose("b", pad2), expose("c", pad3), expose("d", pad4),
                 expose("e", pad5), expose("f", pad6),
                 mission("drive", vdrive, vStartDrive, vCancelDrive).range(0.0f, 10.0f).unit("m").progressMax(2.0f)
                     .describe("drive straight"),
                 mission("home", vhome, vStartHome, vCancelHome));

namespace {

nlohmann::json load() {
  std::ifstream in(std::string(HUBWIRE_VECTORS_DIR) + "/missions/frames.json");
  EXPECT_TRUE(in.good());
  return in.good() ? nlohmann::json::parse(in) : nlohmann::json();
}

TEST(MissionVectors, FramesEncodeToTheirWireBytes) {
  nlohmann::json doc = load();
  size_t n = 0;
  for (auto& v : doc["vectors"]) {
    Bytes payload = hex(v["payload"]);
    uint8_t out[300];
    size_t len = encodeFrame(v["type"], v["seq"], v["id"], payload.data(), (uint8_t)payload.size(), out);
    EXPECT_EQ(toHex(out, len), v["wire"].get<std::string>()) << v["name"];
    ++n;
  }
  EXPECT_GE(n, 40u);
}

TEST(MissionVectors, TheDescriptorEntriesAreTheVectors) {
  nlohmann::json want = nlohmann::json::parse(load()["descriptor"].get<std::string>());
  nlohmann::json mine = nlohmann::json::parse(std::string(vrover.json, vrover.jsonLength));
  size_t n = 0;
  for (auto& w : want["ch"]) {
    int id = w["id"];
    ASSERT_LE(id, (int)mine["ch"].size());
    EXPECT_EQ(mine["ch"][id - 1], w);
    ++n;
  }
  EXPECT_EQ(n, 2u);
}

class MissionScenario : public MissionHub {
 protected:
  std::map<std::string, nlohmann::json> byName;
  std::vector<RxFrame> queue;  // frames the device sent, not yet matched (heartbeats left out)
  std::map<int, uint8_t> seqOf;  // a device update's seq in the vectors -> the device's own

  void pull(uint32_t ms = 0) {
    for (auto& f : step(ms))
      if (f.type != kMsgHeartbeat) queue.push_back(f);
  }
  // Makes the sketch report what an update of the vectors says (the device sends it on its own).
  bool report(const nlohmann::json& m, uint8_t id) {
    std::string kind = m["update"];
    Bytes value = m.contains("value") ? hex(m["value"]) : Bytes();
    float f = 0;
    if (value.size() == 4) memcpy(&f, value.data(), 4);
    if (id == 7 && kind == "progress") return device.progress(vdrive, f);
    if (id == 7 && kind == "succeeded") return device.finish(vdrive, f);
    if (id == 7 && kind == "failed") return device.fail(vdrive, (uint8_t)m["code"].get<int>());
    if (id == 8 && kind == "progress") return device.progress(vhome);
    if (id == 8 && kind == "succeeded") return device.finish(vhome);
    return kind == "cancelled";  // the cancel's answer brought it
  }
  void play(const nlohmann::json& scenario) {
    const auto& steps = scenario["steps"];
    for (size_t i = 0; i < steps.size(); ++i) {
      const nlohmann::json& v = byName.at(steps[i].get<std::string>());
      SCOPED_TRACE(v["name"].get<std::string>());
      uint8_t type = v["type"], id = v["id"];
      int seq = v["seq"];
      Bytes payload = hex(v["payload"]);
      if (v["direction"] == "hub") {
        if (type == kMsgAck && seqOf.count(seq)) {
          // An ACK followed by the same update again: the ACK was lost, and the device retries.
          if (i + 2 < steps.size() && steps[i + 1] == steps[i - 1]) {
            pull(HUBWIRE_EVENT_RETRY_MS);
            continue;
          }
          sendFrame(stream, type, seqOf[seq], id, payload);
        } else {
          sendFrame(stream, type, (uint8_t)seq, id, payload);
        }
        pull();
        continue;
      }
      if (type == kMsgMission && queue.empty()) {
        ASSERT_TRUE(report(v["message"], id));
        pull();
      }
      ASSERT_FALSE(queue.empty());
      RxFrame got = queue.front();
      queue.erase(queue.begin());
      EXPECT_EQ(got.type, type);
      EXPECT_EQ(got.id, id);
      EXPECT_EQ(toHex(got.payload.data(), got.payload.size()), v["payload"].get<std::string>());
      if (type != kMsgMission) {
        EXPECT_EQ(got.seq, seq);
      } else if (seqOf.count(seq)) {
        EXPECT_EQ(got.seq, seqOf[seq]);  // a retry keeps its seq
      } else {
        seqOf[seq] = got.seq;
      }
    }
    EXPECT_TRUE(queue.empty());
    if (scenario.contains("sketch_starts")) {
      EXPECT_EQ(vStarts, scenario["sketch_starts"].get<int>());
    }
    if (scenario.contains("sketch_cancels")) {
      EXPECT_EQ(vCancels, scenario["sketch_cancels"].get<int>());
    }
  }
};

TEST_F(MissionScenario, TheDevicePlaysEveryScenario) {
  nlohmann::json doc = load();
  for (auto& v : doc["vectors"]) byName[v["name"]] = v;
  size_t played = 0;
  for (auto& s : doc["scenarios"]) {
    SCOPED_TRACE(s["name"].get<std::string>());
    // A device plays a scenario whose updates are of runs it started (not the hub's unknown run).
    bool deviceCan = true;
    for (auto& name : s["steps"]) {
      const auto& m = byName.at(name.get<std::string>())["message"];
      if (m["kind"] == "mission_update" && m["run"] != 1 && m["run"] != 2) deviceCan = false;
    }
    if (!deviceCan) continue;
    vdrive = decltype(vdrive)();
    vhome = decltype(vhome)();
    vStarts = vCancels = 0;
    missionLink = MissionLink();
    queue.clear();
    seqOf.clear();
    device.~Session();  // a board just booted
    new (&device) Session(port);
    ASSERT_TRUE(device.begin(vrover, 1));
    link();
    drain(stream);
    play(s);
    ++played;
  }
  EXPECT_EQ(played, doc["scenarios"].size() - 1);
}

}  // namespace
