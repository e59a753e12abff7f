// Reading id 0, the link itself, asks for the board id (PROTOCOL.md 3.4): a board with one answers
// with it, a board without one answers as it answers any unknown channel.
#include <gtest/gtest.h>

#include "fakes.h"
#include "hubwire/channels/declare.h"
#include "hubwire/session/session.h"

using namespace hubwire;
using namespace hubwire::test;

namespace {

uint8_t level;
HUBWIRE_CHANNELS(tiny, "tiny", expose("level", level));

struct Board {
  FakeStream stream;
  FakeClock clock;
  Port port{stream, clock};
  hubwire::Session device{port};
  Board() { EXPECT_TRUE(device.begin(tiny, 3)); }
  void link() {
    sendFrame(stream, '*', 0, 0, hubHello(9));
    device.update();
    drain(stream);
  }
  // The device's one answer to `R` id 0 with this payload.
  RxFrame readId(uint8_t seq, const Bytes& payload = Bytes()) {
    sendFrame(stream, 'R', seq, 0, payload);
    device.update();
    auto frames = drain(stream);
    EXPECT_EQ(frames.size(), 1u);
    return frames.empty() ? RxFrame{} : frames[0];
  }
};

TEST(BoardId, ABoardWithAnIdAnswersWithIt) {
  Board b;
  b.stream.boardId = hex("0a1b2c3d4e5f");
  b.link();
  RxFrame f = b.readId(4);
  EXPECT_EQ(f.type, 'r');
  EXPECT_EQ(f.seq, 4);
  EXPECT_EQ(f.id, 0);
  EXPECT_EQ(toHex(f.payload.data(), f.payload.size()), "0a1b2c3d4e5f");
}

TEST(BoardId, ABoardWithoutOneAnswersUnknownChannel) {
  Board b;
  b.link();
  RxFrame f = b.readId(5);
  EXPECT_EQ(f.type, kMsgNak);
  EXPECT_EQ(f.payload, Bytes(1, kErrUnknownChannel));
}

TEST(BoardId, AReadWithAPayloadOrBeforeTheHandshakeIsRefused) {
  Board b;
  b.stream.boardId = hex("01");
  RxFrame f = b.readId(6);  // not linked yet
  EXPECT_EQ(f.payload, Bytes(1, kErrNotLinked));
  b.link();
  f = b.readId(7, Bytes(1));
  EXPECT_EQ(f.type, kMsgNak);
  EXPECT_EQ(f.payload, Bytes(1, kErrUnknownChannel));
  f = b.readId(8);
  EXPECT_EQ(f.type, 'r');
  EXPECT_EQ(f.payload, hex("01"));
}

}  // namespace
