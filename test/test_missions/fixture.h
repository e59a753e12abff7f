// A small hub around one device session for the mission suites: frames in, frames out, the clock.
#ifndef HUBWIRE_TEST_MISSIONS_FIXTURE_H
#define HUBWIRE_TEST_MISSIONS_FIXTURE_H

#include <gtest/gtest.h>

#include <vector>

#include "fakes.h"
#include "frames.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

namespace hubwire {
namespace test {

class MissionHub : public ::testing::Test {
 protected:
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  Session device{port};
  uint8_t hubSeq = 0x60;

  void SetUp() override {
    missionLink = MissionLink();  // one program, a new session each test
    hubLink.owner = nullptr;
  }
  std::vector<RxFrame> step(uint32_t ms = 0) {
    clock.now += ms;
    device.update();
    return drain(stream);
  }
  void link(uint32_t nonce = 7) {
    sendFrame(stream, kMsgHello, 0, 0, hubHello(nonce));
    step();
  }
  // Sends a frame, runs one update, and returns the answer with the frame's seq and id; the other
  // frames the device sent are kept in `others`.
  RxFrame ask(uint8_t type, uint8_t seq, uint8_t id, const Bytes& payload = Bytes()) {
    sendFrame(stream, type, seq, id, payload);
    RxFrame answer{0, 0, 0, {}};
    others.clear();
    for (auto& f : step()) {
      bool mine = answer.type == 0 && f.seq == seq && f.id == id &&
                  (f.type == kMsgResponse || f.type == kMsgAck || f.type == kMsgNak);
      if (mine) answer = f;
      else others.push_back(f);
    }
    return answer;
  }
  RxFrame control(uint8_t id, const Bytes& payload) { return ask(kMsgControl, ++hubSeq, id, payload); }
  RxFrame start(uint8_t id, const Bytes& goal = Bytes()) {
    Bytes p{kMissionStart};
    p.insert(p.end(), goal.begin(), goal.end());
    return control(id, p);
  }
  RxFrame cancel(uint8_t id, uint8_t run) { return control(id, Bytes{kMissionCancel, run}); }
  RxFrame state(uint8_t id) { return ask(kMsgRequest, ++hubSeq, id); }
  void ack(const RxFrame& f, uint8_t type = kMsgAck) { sendFrame(stream, type, f.seq, f.id, type == kMsgNak ? Bytes{kErrBadValue} : Bytes()); }

  static std::vector<RxFrame> only(const std::vector<RxFrame>& fs, uint8_t type) {
    std::vector<RxFrame> r;
    for (auto& f : fs)
      if (f.type == type) r.push_back(f);
    return r;
  }
  std::vector<RxFrame> others;
};

inline Bytes nak(uint8_t code) { return Bytes{code}; }
template <typename T>
Bytes update(uint8_t run, uint8_t kind, T value) {
  Bytes b{run, kind};
  Bytes v = le(value);
  b.insert(b.end(), v.begin(), v.end());
  return b;
}
inline Bytes update(uint8_t run, uint8_t kind) { return Bytes{run, kind}; }

}  // namespace test
}  // namespace hubwire

#endif
