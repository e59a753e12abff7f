// The golden vectors of large values and lists (test/vectors/large/frames.json, written by
// large_frames.py): every exchange played against a device declaring the vectors' channels, with
// its exact answers, its dropped count and the value it leaves; and the device's own fragments
// (a large read, a large sample) byte for byte. A program of its own: the reassembly buffer is the
// one of this table (200 bytes), so that a 201-byte total is over capacity as the vectors say.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "fakes.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

using namespace hubwire;
using namespace hubwire::test;
using nlohmann::json;

namespace {

uint8_t big[200];
List<int16_t, 8> path;

HUBWIRE_CHANNELS(vectorsTable, "large",
  expose("big", big).writable().streamable(),                 // 1
  expose("path", path).writable().range(-1000, 1000));        // 2

json load() {
  std::ifstream in(std::string(HUBWIRE_VECTORS_DIR) + "/large/frames.json");
  EXPECT_TRUE(in.good());
  return json::parse(in);
}

class LargeVectors : public ::testing::Test {
 protected:
  json doc = load();
  std::map<std::string, json> byName;
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  hubwire::Session device{port};

  void SetUp() override {
    for (auto& v : doc["vectors"]) byName[v["name"].get<std::string>()] = v;
    memset(big, 0, sizeof(big));
    path.clear();
    ASSERT_TRUE(device.begin(vectorsTable, 1));
    sendFrame(stream, '*', 0, 0, hubHello(5));
    device.update();
    ASSERT_TRUE(device.linked());
    device.update();  // the first heartbeat
    drain(stream);
  }

  // Feeds the wire bytes of the named vectors and returns the device's frames, heartbeats aside.
  std::vector<RxFrame> play(const json& names) {
    std::vector<RxFrame> got;
    for (auto& n : names) {
      Bytes w = hex(byName.at(n.get<std::string>())["wire"]);
      stream.in.insert(stream.in.end(), w.begin(), w.end());
      while (!stream.in.empty()) device.update();
      for (auto& f : drain(stream))
        if (f.type != 'H') got.push_back(f);
    }
    return got;
  }

  void expectFrames(const std::vector<RxFrame>& got, const json& names, const std::string& what) {
    ASSERT_EQ(got.size(), names.size()) << what;
    for (size_t i = 0; i < got.size(); ++i) {
      const json& v = byName.at(names[i].get<std::string>());
      EXPECT_EQ(got[i].type, v["type"].get<int>()) << what << " #" << i;
      EXPECT_EQ(got[i].seq, v["seq"].get<int>()) << what << " #" << i;
      EXPECT_EQ(got[i].id, v["id"].get<int>()) << what << " #" << i;
      EXPECT_EQ(toHex(got[i].payload.data(), got[i].payload.size()), v["payload"].get<std::string>()) << what << " #" << i;
    }
  }
};

std::string valueHex(int channel) {
  if (channel == 1) return toHex(big, sizeof(big));
  Bytes w(1, path.count);
  for (uint8_t i = 0; i < path.count; ++i) {
    Bytes e = le(path.items[i]);
    w.insert(w.end(), e.begin(), e.end());
  }
  return toHex(w.data(), w.size());
}

TEST_F(LargeVectors, DeviceAsTheVectorsDescribeIt) {
  EXPECT_EQ(doc["max_payload"].get<int>(), HUBWIRE_MAX_PAYLOAD);
  EXPECT_EQ(doc["big"].get<std::string>().size(), 2 * sizeof(big));
  EXPECT_EQ((HubwireLarge<true, void>::capacity), sizeof(big));  // the largest large writable value
}

TEST_F(LargeVectors, EveryExchange) {
  std::set<std::string> used;
  for (auto& e : doc["exchanges"]) {
    std::string name = e["name"];
    SCOPED_TRACE(name);
    TearDown();
    device.~Session();
    new (&device) hubwire::Session(port);
    stream.in.clear();
    SetUp();
    uint16_t dropped = device.counters().dropped;
    std::vector<RxFrame> got = play(e["send"]);
    expectFrames(got, e["answer"], name);
    EXPECT_EQ(device.counters().dropped - dropped, e["dropped"].get<int>());
    if (e.contains("value")) {
      EXPECT_EQ(valueHex(e["value"]["channel"]), e["value"]["hex"].get<std::string>());
    }
    for (auto& n : e["send"]) used.insert(n);
    for (auto& n : e["answer"]) used.insert(n);
  }
  // A large sample: subscribed and sent at once, from the variable, in the vectors' fragments.
  memcpy(big, hex(doc["big"]).data(), sizeof(big));
  sendFrame(stream, 'S', 0x30, 1, le<uint16_t>(1000));
  device.update();
  std::vector<RxFrame> got;
  for (auto& f : drain(stream))
    if (f.type != 'H' && f.type != 0x07) got.push_back(f);
  json samples = json::array();
  for (auto& v : doc["vectors"])
    if (v["name"].get<std::string>().find("device streams a sample") == 0) samples.push_back(v["name"]);
  EXPECT_EQ(samples.size(), 8u);
  expectFrames(got, samples, "sample");
  for (auto& n : samples) used.insert(n);
  // every vector of the file was played or compared
  for (auto& v : doc["vectors"]) EXPECT_TRUE(used.count(v["name"])) << v["name"];
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
