// The device against the session rules of docs/PROTOCOL.md (test/vectors/session/rules.json):
// every device_script is played step by step on a fake stream and clock, and every string_bytes
// vector is written to a str channel and read back.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "fakes.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

using namespace hubwire;
using namespace hubwire::test;
using nlohmann::json;

namespace {

// The channels rules.json names (DEVICE_CHANNELS in test/vectors/session_rules.py).
uint8_t level;
char name[5];
Event<uint8_t> bump;
bool beep(uint8_t v) { return v != 0; }

HUBWIRE_CHANNELS(rules, "rules",
  expose("level", level).writable().streamable().range(0, 100),  // 1
  expose("name", name).writable(),                                // 2
  control("beep", beep),                                          // 3
  event("bump", bump));                                           // 4

json vectors(const std::string& kind) {
  std::ifstream in(std::string(HUBWIRE_VECTORS_DIR) + "/session/rules.json");
  json all = json::parse(in), out = json::array();
  for (auto& v : all["vectors"])
    if (v["kind"] == kind) out.push_back(v);
  return out;
}

struct Rig {
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  Session device{port};
  Rig() {
    level = 0;
    std::strcpy(name, "");
    bump = Event<uint8_t>();
    device.begin(rules, 0x1234);
  }
};

std::string show(const RxFrame& f) {
  return "type " + std::to_string(f.type) + " seq " + std::to_string(f.seq) + " id " + std::to_string(f.id) +
         " payload " + toHex(f.payload.data(), f.payload.size());
}

// One expected frame: exact, or a device hello judged by its DEVICE and REPLY flags and its size (32
// bytes with the digest, 16 without: `digest` when the vector says, either otherwise).
void expectFrame(const json& want, const RxFrame& got, const std::string& where) {
  EXPECT_EQ(got.type, want["type"].get<int>()) << where << ": got " << show(got);
  EXPECT_EQ(got.seq, want["seq"].get<int>()) << where << ": got " << show(got);
  EXPECT_EQ(got.id, want["id"].get<int>()) << where << ": got " << show(got);
  if (want.contains("hello_flags")) {
    // 32 bytes with the descriptor digest once it has heard a hub that takes them, 16 before
    if (want.contains("digest"))
      ASSERT_EQ(got.payload.size(), want["digest"].get<bool>() ? 32u : 16u) << where << ": hello size (digest)";
    else
      ASSERT_TRUE(got.payload.size() == 16u || got.payload.size() == 32u) << where << ": " << got.payload.size();
    EXPECT_EQ(got.payload[0], 1) << where << ": version";
    EXPECT_EQ(got.payload[1] & 3, want["hello_flags"].get<int>()) << where << ": flags";
  } else {
    EXPECT_EQ(toHex(got.payload.data(), got.payload.size()), want["payload"].get<std::string>())
        << where << ": got " << show(got);
  }
}

void playStep(Rig& rig, const json& s, const std::string& where) {
  rig.clock.now += s["advance_ms"].get<uint32_t>();
  for (auto& f : s["hub"])
    sendFrame(rig.stream, (uint8_t)f["type"].get<int>(), (uint8_t)f["seq"].get<int>(),
              (uint8_t)f["id"].get<int>(), hex(f["payload"].get<std::string>()));
  if (s.contains("emit")) {
    Bytes v = hex(s["emit"]["value"].get<std::string>());
    ASSERT_EQ(s["emit"]["id"].get<int>(), 4) << where;
    ASSERT_TRUE(rig.device.emit(bump, v.at(0))) << where;
  }
  rig.device.update();
  std::vector<RxFrame> got = drain(rig.stream);
  const json& want = s["device"];
  ASSERT_EQ(got.size(), want.size()) << where << ": frames sent" << (got.empty() ? "" : ", first " + show(got[0]));
  for (size_t i = 0; i < got.size(); ++i) expectFrame(want[i], got[i], where + ", frame " + std::to_string(i));
}

TEST(ProtocolRules, DeviceScripts) {
  json all = vectors("device_script");
  ASSERT_GE(all.size(), 10u);
  for (auto& v : all) {
    Rig rig;
    int n = 0;
    for (auto& s : v["steps"]) {
      playStep(rig, s, v["name"].get<std::string>() + ", step " + std::to_string(n++));
      if (::testing::Test::HasFatalFailure()) return;
    }
  }
}

TEST(ProtocolRules, StringsAreStoredAsSent) {
  json all = vectors("string_bytes");
  ASSERT_GE(all.size(), 1u);
  for (auto& v : all) {
    ASSERT_EQ(v["type"]["c"].get<int>(), 4) << "the rig's str channel holds 4 bytes";
    Rig rig;
    sendFrame(rig.stream, '*', 0, 0, hubHello(9));
    rig.device.update();
    drain(rig.stream);
    Bytes p = hex(v["hex"].get<std::string>());
    sendFrame(rig.stream, 'C', 1, 2, p);
    sendFrame(rig.stream, 'R', 2, 2);
    rig.device.update();
    std::vector<RxFrame> got = drain(rig.stream);
    ASSERT_EQ(got.size(), 2u) << v["name"];
    EXPECT_EQ(got[0].type, 0x07) << v["name"] << ": " << show(got[0]);
    EXPECT_EQ(got[1].type, 'r') << v["name"];
    EXPECT_EQ(got[1].payload, p) << v["name"];
    EXPECT_EQ(std::string(name), std::string(p.begin() + 1, p.end())) << v["name"];
  }
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
