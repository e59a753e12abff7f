// The event queue alone: order, capacity, seq per event (kept by retries), the retry interval and
// which answers remove the head.
#include <gtest/gtest.h>

#include "hubwire/session/event_queue.h"

using hubwire::EventQueue;

namespace {

EventQueue fresh() { return EventQueue(); }  // value-initialised, as inside the session

TEST(EventQueue, KeepsOrderAndCopiesOfTheValues) {
  EventQueue q = fresh();
  uint16_t a = 0x1234;
  uint8_t b = 7;
  ASSERT_TRUE(q.push(3, &a, sizeof(a)));
  a = 0;  // the queue holds its own copy
  ASSERT_TRUE(q.push(5, &b, sizeof(b)));
  EXPECT_EQ(q.size(), 2);
  const EventQueue::Entry& first = q.send(0);
  EXPECT_EQ(first.id, 3);
  ASSERT_EQ(first.len, 2);
  EXPECT_EQ(first.data[0], 0x34);
  EXPECT_EQ(first.data[1], 0x12);
  ASSERT_TRUE(q.acked(q.seq(), 3));
  const EventQueue::Entry& second = q.send(1);
  EXPECT_EQ(second.id, 5);
  EXPECT_EQ(second.len, 1);
  EXPECT_EQ(second.data[0], 7);
}

TEST(EventQueue, RefusesWhenFullAndTakesMoreOnceAcked) {
  EventQueue q = fresh();
  uint8_t v = 1;
  for (int i = 0; i < HUBWIRE_EVENT_QUEUE; ++i) ASSERT_TRUE(q.push((uint8_t)(i + 1), &v, 1));
  EXPECT_FALSE(q.push(9, &v, 1));
  EXPECT_EQ(q.size(), HUBWIRE_EVENT_QUEUE);
  q.send(0);
  ASSERT_TRUE(q.acked(q.seq(), 1));
  EXPECT_TRUE(q.push(9, &v, 1));  // the ring wraps: the freed slot is reused
  for (int i = 1; i < HUBWIRE_EVENT_QUEUE; ++i) {
    EXPECT_EQ(q.send(0).id, i + 1);
    ASSERT_TRUE(q.acked(q.seq(), (uint8_t)(i + 1)));
  }
  EXPECT_EQ(q.send(0).id, 9);
}

TEST(EventQueue, NewEventNewSeqRetryKeepsIt) {
  EventQueue q = fresh();
  uint8_t v = 0;
  q.push(1, &v, 1);
  q.push(1, &v, 1);
  q.send(0);
  uint8_t first = q.seq();
  q.send(HUBWIRE_EVENT_RETRY_MS);  // a retry
  EXPECT_EQ(q.seq(), first);
  ASSERT_TRUE(q.acked(first, 1));
  q.send(HUBWIRE_EVENT_RETRY_MS + 1);
  EXPECT_EQ(q.seq(), (uint8_t)(first + 1));
}

TEST(EventQueue, DueWhenNewOrUnansweredForTheRetryInterval) {
  EventQueue q = fresh();
  EXPECT_FALSE(q.due(0));  // nothing queued
  uint8_t v = 0;
  q.push(2, &v, 1);
  EXPECT_TRUE(q.due(0));  // never sent
  q.send(1000);
  EXPECT_FALSE(q.due(1000));
  EXPECT_FALSE(q.due(1000 + HUBWIRE_EVENT_RETRY_MS - 1));
  EXPECT_TRUE(q.due(1000 + HUBWIRE_EVENT_RETRY_MS));
  q.send(65530);  // across the 16-bit clock's wrap
  EXPECT_FALSE(q.due((uint16_t)(65530 + HUBWIRE_EVENT_RETRY_MS - 1)));
  EXPECT_TRUE(q.due((uint16_t)(65530 + HUBWIRE_EVENT_RETRY_MS)));
  q.retryNow(40);
  EXPECT_TRUE(q.due(40));
}

TEST(EventQueue, OnlyTheAnswerToTheHeadInFlightRemovesIt) {
  EventQueue q = fresh();
  uint8_t v = 0;
  q.push(4, &v, 1);
  EXPECT_FALSE(q.acked(q.seq(), 4));  // not sent yet
  q.send(0);
  EXPECT_FALSE(q.acked((uint8_t)(q.seq() + 1), 4));  // another seq
  EXPECT_FALSE(q.acked(q.seq(), 5));                 // another channel
  EXPECT_EQ(q.size(), 1);
  EXPECT_TRUE(q.acked(q.seq(), 4));
  EXPECT_EQ(q.size(), 0);
  EXPECT_FALSE(q.acked(q.seq(), 4));  // a duplicate answer
  EXPECT_FALSE(q.due(0));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
