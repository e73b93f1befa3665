// The cloud merger's synchronisation policy (cloud_merger_sync.h) on stamp sequences: the
// simulator's rig phases, a dead sensor, late and repeated clouds, a looping bag.
#include "gmm_localization/ros/cloud_merger_sync.h"

#include <gtest/gtest.h>

namespace gmm_localization {
namespace node {
namespace {

constexpr int64_t kMs = 1000000;  // ns per ms
constexpr int64_t kPeriod = 100 * kMs;
// Rig phases of the simulator (0, 0.23, 0.51, 0.74 of a period); a revolution is published
// (arrives) at its end, one period after its stamp, plus 5 ms of transport.
constexpr int64_t kPhase[4] = {0, 23 * kMs, 51 * kMs, 74 * kMs};

MergeInput cloud(size_t sensor, int64_t stamp_ns, double arrival_s = -1.0) {
  MergeInput in;
  in.sensor = sensor;
  in.stamp_ns = stamp_ns;
  in.arrival_s = arrival_s >= 0.0 ? arrival_s : (stamp_ns + kPeriod + 5 * kMs) * 1e-9;
  in.cloud = std::make_shared<CloudData>();
  return in;
}

TEST(MergeSynchronizer, FourUnsynchronisedSensorsMergeOneRevolutionEach) {
  MergeSynchronizer sync({});
  std::vector<MergeCycle> out;
  const int64_t t0 = 1000 * kPeriod;
  for (int rev = 0; rev < 20; ++rev) {
    for (size_t s = 0; s < 4; ++s) {
      const MergeInput in = cloud(s, t0 + rev * kPeriod + kPhase[s]);
      ASSERT_EQ(sync.add(in, out), MergeVerdict::kAccepted);
      // The timer between arrivals never fires: the last cloud comes 74 ms after the first.
      EXPECT_FALSE(sync.poll(in.arrival_s + 1e-3).has_value());
    }
  }
  ASSERT_EQ(out.size(), 20u);
  for (int rev = 0; rev < 20; ++rev) {
    const MergeCycle& c = out[rev];
    EXPECT_EQ(c.closed, MergeCycle::Closed::kComplete);
    EXPECT_EQ(c.stamp_ns, t0 + rev * kPeriod) << "the earliest input stamp";
    ASSERT_EQ(c.inputs.size(), 4u);
    EXPECT_TRUE(c.missing.empty());
    for (size_t s = 0; s < 4; ++s) {
      EXPECT_EQ(c.inputs[s].sensor, s);
      EXPECT_EQ(c.inputs[s].stamp_ns, t0 + rev * kPeriod + kPhase[s]);
    }
  }
  EXPECT_EQ(sync.counters().complete, 20u);
  EXPECT_EQ(sync.counters().incomplete, 0u);
}

TEST(MergeSynchronizer, ArrivalOrderDoesNotMatter) {
  MergeSynchronizer sync({});
  std::vector<MergeCycle> out;
  const int64_t t = 5000 * kPeriod;
  for (size_t s : {2u, 0u, 3u, 1u})
    EXPECT_EQ(sync.add(cloud(s, t + kPhase[s]), out), MergeVerdict::kAccepted);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stamp_ns, t);
  EXPECT_EQ(out[0].inputs[1].sensor, 1u);
}

TEST(MergeSynchronizer, DeadSensorTimesOutAndIsNamed) {
  MergeSynchronizer sync({});
  std::vector<MergeCycle> out;
  const int64_t t = 2000 * kPeriod;
  sync.add(cloud(0, t + kPhase[0]), out);
  sync.add(cloud(1, t + kPhase[1]), out);
  sync.add(cloud(3, t + kPhase[3]), out);
  ASSERT_TRUE(out.empty());
  const double first_arrival = (t + kPeriod + 5 * kMs) * 1e-9;
  EXPECT_FALSE(sync.poll(first_arrival + 0.119).has_value());
  auto c = sync.poll(first_arrival + 0.121);
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->closed, MergeCycle::Closed::kTimeout);
  EXPECT_EQ(c->missing, std::vector<size_t>({2}));
  EXPECT_EQ(c->inputs.size(), 3u);
  EXPECT_EQ(sync.counters().incomplete, 1u);
  EXPECT_FALSE(sync.poll(first_arrival + 1.0).has_value()) << "nothing open any more";
}

TEST(MergeSynchronizer, NextSetClosesTheOpenOneWithoutTheTimer) {
  MergeSynchronizer sync({});
  std::vector<MergeCycle> out;
  const int64_t t = 3000 * kPeriod;
  sync.add(cloud(0, t), out);
  sync.add(cloud(1, t + kPhase[1]), out);
  // A second cloud of sensor 0 (its clock runs early: 90 ms) closes the set.
  EXPECT_EQ(sync.add(cloud(0, t + 90 * kMs), out), MergeVerdict::kAccepted);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].closed, MergeCycle::Closed::kRepeatedSensor);
  EXPECT_EQ(out[0].missing, std::vector<size_t>({2, 3}));
  // A stamp beyond the spread (sensor 2, 120 ms after the new set's first stamp) closes it too.
  EXPECT_EQ(sync.add(cloud(2, t + 210 * kMs), out), MergeVerdict::kAccepted);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].closed, MergeCycle::Closed::kNextCycle);
  EXPECT_EQ(out[1].stamp_ns, t + 90 * kMs);
  // Sensor 1's next revolution, 100 ms after its last: beyond the spread, a new set as well.
  EXPECT_EQ(sync.add(cloud(1, t + 310 * kMs), out), MergeVerdict::kAccepted);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[2].closed, MergeCycle::Closed::kNextCycle);
  EXPECT_TRUE(sync.cycleOpen());
}

TEST(MergeSynchronizer, LateAndOutOfWindowCloudsAreDroppedAndCounted) {
  MergeSynchronizer sync({});
  std::vector<MergeCycle> out;
  const int64_t t = 4000 * kPeriod;
  for (size_t s = 0; s < 4; ++s) sync.add(cloud(s, t + kPhase[s]), out);
  ASSERT_EQ(out.size(), 1u);
  // A cloud stamped before the last output: late.
  EXPECT_EQ(sync.add(cloud(2, t - 10 * kMs), out), MergeVerdict::kLate);
  // Open the next set, then offer a cloud older than its window.
  sync.add(cloud(1, t + kPeriod + 50 * kMs), out);
  EXPECT_EQ(sync.add(cloud(3, t + 20 * kMs), out), MergeVerdict::kOutOfWindow);
  // An older repeat of a sensor already in the set.
  EXPECT_EQ(sync.add(cloud(1, t + kPeriod + 40 * kMs), out), MergeVerdict::kOutOfWindow);
  EXPECT_EQ(sync.add(cloud(7, t + kPeriod), out), MergeVerdict::kUnknownSensor);
  EXPECT_EQ(sync.counters().late, 1u);
  EXPECT_EQ(sync.counters().out_of_window, 2u);
  EXPECT_EQ(out.size(), 1u);
}

TEST(MergeSynchronizer, TimeGoingBackwardsResetsAndRecovers) {
  MergeSynchronizer sync({});
  std::vector<MergeCycle> out;
  const int64_t t = 9000 * kPeriod;
  for (size_t s = 0; s < 4; ++s) sync.add(cloud(s, t + kPhase[s]), out);
  sync.add(cloud(0, t + kPeriod), out);  // an open set when the bag loops
  ASSERT_EQ(out.size(), 1u);
  // The bag loops: back by 60 s.
  const int64_t back = t - 600 * kPeriod;
  EXPECT_EQ(sync.add(cloud(0, back), out), MergeVerdict::kAccepted);
  EXPECT_EQ(sync.counters().resets, 1u);
  for (size_t s = 1; s < 4; ++s) sync.add(cloud(s, back + kPhase[s]), out);
  ASSERT_EQ(out.size(), 2u) << "the discarded open set is not published";
  EXPECT_EQ(out[1].stamp_ns, back);
  EXPECT_TRUE(out[1].missing.empty());
  // A small step back (a late cloud) is not a reset.
  EXPECT_EQ(sync.add(cloud(1, back - 10 * kMs), out), MergeVerdict::kLate);
  EXPECT_EQ(sync.counters().resets, 1u);
}

TEST(MergeSynchronizer, SingleSensorPassesThrough) {
  MergeSyncOptions o;
  o.sensors = 1;
  MergeSynchronizer sync(o);
  std::vector<MergeCycle> out;
  for (int i = 0; i < 5; ++i) sync.add(cloud(0, (100 + i) * kPeriod), out);
  ASSERT_EQ(out.size(), 5u);
  for (const auto& c : out) EXPECT_EQ(c.closed, MergeCycle::Closed::kComplete);
}

TEST(MergeSyncOptions, Validation) {
  EXPECT_TRUE(MergeSyncOptions().validate().empty());
  MergeSyncOptions o;
  o.sensors = 0;
  EXPECT_NE(o.validate().find("sensors"), std::string::npos);
  o = MergeSyncOptions();
  o.max_wait_s = 0.0;
  EXPECT_NE(o.validate().find("max_wait_s"), std::string::npos);
  o = MergeSyncOptions();
  o.backwards_reset_s = 0.05;  // shorter than the spread
  EXPECT_NE(o.validate().find("backwards_reset_s"), std::string::npos);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
