// The subscriptions alone: slots, granted intervals, when samples fall due, the schedule kept
// without drift, and the 16-bit clock's wrap.
#include <gtest/gtest.h>

#include "hubwire/session/streams.h"

using hubwire::Streams;
using hubwire::Subscription;

namespace {

Subscription* find(Streams& s, uint8_t id) {
  for (uint8_t i = 0; i < HUBWIRE_MAX_STREAMS; ++i)
    if (s[i].id == id) return &s[i];
  return nullptr;
}

TEST(Streams, SubscribeIsDueAtOnceAndReportsTimeSinceSubscribing) {
  Streams s = Streams();
  uint16_t interval = 100;
  ASSERT_TRUE(s.subscribe(3, interval, 500));
  EXPECT_EQ(interval, 100);
  Subscription* sub = find(s, 3);
  ASSERT_NE(sub, nullptr);
  EXPECT_TRUE(sub->due(500));
  EXPECT_EQ(sub->since(520), 20);
  EXPECT_EQ(sub->seq, 0);
  sub->sent(520);
  EXPECT_EQ(sub->seq, 1);
  EXPECT_EQ(sub->since(530), 10);
}

TEST(Streams, IntervalsAreClampedToWhatIsGranted) {
  Streams s = Streams();
  uint16_t tiny = 1, huge = 65000;
  ASSERT_TRUE(s.subscribe(1, tiny, 0));
  ASSERT_TRUE(s.subscribe(2, huge, 0));
  EXPECT_EQ(tiny, HUBWIRE_MIN_STREAM_INTERVAL_MS);
  EXPECT_EQ(huge, hubwire::kMaxStreamIntervalMs);
  EXPECT_EQ(find(s, 1)->interval, HUBWIRE_MIN_STREAM_INTERVAL_MS);
}

TEST(Streams, ScheduleKeepsItsPaceUnlessFarBehind) {
  Streams s = Streams();
  uint16_t interval = 100;
  s.subscribe(7, interval, 1000);
  Subscription& sub = *find(s, 7);
  sub.sent(1003);  // late by 3 ms: the next one is still due at 1100
  EXPECT_FALSE(sub.due(1099));
  EXPECT_TRUE(sub.due(1100));
  sub.sent(1350);  // more than an interval behind: the schedule restarts from now
  EXPECT_FALSE(sub.due(1449));
  EXPECT_TRUE(sub.due(1450));
}

TEST(Streams, DueAcrossTheClocksWrapAndForLongIntervals) {
  Streams s = Streams();
  uint16_t interval = 50000;  // past 32.8 s: a signed comparison would get it wrong
  s.subscribe(2, interval, 60000);
  Subscription& sub = *find(s, 2);
  sub.sent(60000);
  EXPECT_FALSE(sub.due((uint16_t)(60000 + 49999)));
  EXPECT_TRUE(sub.due((uint16_t)(60000 + 50000)));
}

TEST(Streams, ResubscribingChangesTheIntervalZeroEndsAndClearEndsAll) {
  Streams s = Streams();
  uint16_t interval = 100;
  s.subscribe(4, interval, 0);
  find(s, 4)->sent(10);
  interval = 200;
  ASSERT_TRUE(s.subscribe(4, interval, 20));
  Subscription* sub = find(s, 4);
  EXPECT_EQ(sub->interval, 200);
  EXPECT_EQ(sub->seq, 1);  // the same subscription: its seq goes on
  EXPECT_NE(find(s, 0), nullptr);  // the other slots are still free
  interval = 0;
  ASSERT_TRUE(s.subscribe(4, interval, 30));
  EXPECT_EQ(find(s, 4), nullptr);
  EXPECT_EQ(interval, 0);
  interval = 100;
  s.subscribe(5, interval, 0);
  s.clear();
  EXPECT_EQ(find(s, 5), nullptr);
  EXPECT_FALSE(s[0].due(1000));  // a free slot is never due
}

TEST(Streams, FullWhenEverySlotIsTaken) {
  Streams s = Streams();
  uint16_t interval = 100;
  for (uint8_t id = 1; id <= HUBWIRE_MAX_STREAMS; ++id) ASSERT_TRUE(s.subscribe(id, interval, 0));
  EXPECT_FALSE(s.subscribe(HUBWIRE_MAX_STREAMS + 1, interval, 0));
  EXPECT_TRUE(s.subscribe(1, interval, 0));  // an existing one may still change
  interval = 0;
  s.subscribe(1, interval, 0);
  interval = 100;
  EXPECT_TRUE(s.subscribe(HUBWIRE_MAX_STREAMS + 1, interval, 0));  // its slot is free again
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
