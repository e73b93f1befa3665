// The matcher's scan queue: arrival order, bounded, the oldest dropped and counted.

#include "gmm_localization/core/common/drop_oldest_queue.h"

#include <gtest/gtest.h>

namespace gmm_localization {
namespace {

TEST(DropOldestQueue, KeepsArrivalOrderAndDropsTheOldestWhenFull) {
  DropOldestQueue<int> q(3);
  EXPECT_EQ(q.push(1), 0u);
  EXPECT_EQ(q.push(2), 0u);
  EXPECT_EQ(q.push(3), 0u);
  EXPECT_EQ(q.push(4), 1u);  // 1 goes
  EXPECT_EQ(q.push(5), 1u);  // 2 goes
  EXPECT_EQ(q.size(), 3u);
  EXPECT_EQ(q.droppedTotal(), 2u);
  EXPECT_EQ(q.pop(), 3);
  EXPECT_EQ(q.pop(), 4);
  EXPECT_EQ(q.push(6), 0u);
  EXPECT_EQ(q.pop(), 5);
  EXPECT_EQ(q.pop(), 6);
  EXPECT_TRUE(q.empty());
  q.push(7);
  q.push(8);
  EXPECT_EQ(q.clear(), 2u);  // e.g. the scans of a timeline that time left behind
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.droppedTotal(), 4u);
}

TEST(DropOldestQueue, CapacityOneKeepsOnlyTheNewest) {
  DropOldestQueue<int> q(0);  // clamped to 1
  EXPECT_EQ(q.capacity(), 1u);
  q.push(1);
  EXPECT_EQ(q.push(2), 1u);
  EXPECT_EQ(q.pop(), 2);
  EXPECT_TRUE(q.empty());
}

}  // namespace
}  // namespace gmm_localization
