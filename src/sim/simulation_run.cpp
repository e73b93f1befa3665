// Simulation::run: cycle by cycle, ray-cast all sensors, then hand every product to the sink in
// the order it becomes available (a merge of scans and 100-200 Hz samples by time).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <memory>

#include "gmm_localization/sim/simulation.h"

namespace gmm_localization {
namespace sim {
namespace {

struct Event {
  double time;
  int order;  // ties: samples (0) before scans (1)
  std::function<Status()> emit;
};

}  // namespace

Result<SimulationStats> Simulation::run(SimulationSink& sink,
                                        const std::function<void(double)>& progress) const {
  using Clock = std::chrono::steady_clock;
  const auto wall0 = Clock::now();
  SimulationStats stats;
  const double period = lidar_->model().revolutionPeriod();
  double min_phase = period;
  for (const SensorMount& m : config_.rig.sensors) min_phase = std::min(min_phase, m.phase_s);

  InsModel ins(*trajectory_, config_.ins, t_begin_);
  long gt_count = 0;
  auto gtTime = [&](long k) {
    return t_begin_ + static_cast<double>(k) / config_.ground_truth_rate_hz;
  };
  std::vector<Event> queue;
  std::vector<OdomSample> odom;
  std::vector<ImuSample> imu;

  // Queue the samples with time < t_until, then emit every queued event before t_until.
  auto flushUntil = [&](double t_until) -> Status {
    const double t_samples = std::min(t_until, t_end_);
    odom.clear();
    imu.clear();
    ins.advanceTo(t_samples, &odom, &imu);
    for (const OdomSample& o : odom)
      queue.push_back({o.t, 0, [&sink, o]() { return sink.onOdometry(o); }});
    for (const ImuSample& m : imu)
      queue.push_back({m.t, 0, [&sink, m]() { return sink.onImu(m); }});
    for (; gtTime(gt_count) < t_samples; ++gt_count) {
      const VehicleState s = trajectory_->state(gtTime(gt_count));
      queue.push_back({s.t, 0, [&sink, s]() { return sink.onGroundTruth(s); }});
    }
    std::stable_sort(queue.begin(), queue.end(), [](const Event& a, const Event& b) {
      return a.time < b.time || (a.time == b.time && a.order < b.order);
    });
    size_t k = 0;
    for (; k < queue.size() && queue[k].time < t_until; ++k) {
      const Status s = queue[k].emit();
      if (!s) return s;
    }
    queue.erase(queue.begin(), queue.begin() + static_cast<long>(k));
    return Status::success();
  };

  // Cycle c + 1 is ray-cast, merged and deskewed in the background while the sink consumes
  // cycle c (with 2 cores, bag writing then overlaps the ray casting).
  struct Products {
    std::shared_ptr<std::vector<SensorRevolution>> revs;
    std::shared_ptr<MergedScan> merged;
    std::shared_ptr<DeskewedScan> deskewed;
    double seconds = 0.0;
  };
  auto produce = [this, period, min_phase](int64_t c) {
    const auto l0 = Clock::now();
    Products p;
    p.revs = std::make_shared<std::vector<SensorRevolution>>(lidar_->simulateCycle(c));
    if (config_.emit_merged)
      p.merged = std::make_shared<MergedScan>(mergeRevolutions(*p.revs, config_.rig));
    if (config_.emit_deskewed) {
      p.deskewed = std::make_shared<DeskewedScan>();
      p.deskewed->index = c;
      p.deskewed->stamp = c * period + min_phase;
      p.deskewed->base_to_map = trajectory_->pose(p.deskewed->stamp);
      p.deskewed->points =
          deskewToStamp(*p.revs, config_.rig, lidar_->model(), *trajectory_, p.deskewed->stamp);
    }
    p.seconds = std::chrono::duration<double>(Clock::now() - l0).count();
    return p;
  };
  const int64_t end_cycle = first_cycle_ + num_cycles_;
  std::future<Products> next;
  if (num_cycles_ > 0) next = std::async(std::launch::async, produce, first_cycle_);
  for (int64_t c = first_cycle_; c < end_cycle; ++c) {
    Products p = next.get();
    if (c + 1 < end_cycle) next = std::async(std::launch::async, produce, c + 1);
    stats.lidar_wall_seconds += p.seconds;
    double complete = 0.0;
    for (const SensorRevolution& r : *p.revs) {
      stats.rays += r.rays;
      stats.points += r.points.size();
      complete = std::max(complete, r.t_end);
    }
    if (config_.emit_revolutions) {
      auto revs = p.revs;
      for (size_t k = 0; k < revs->size(); ++k)
        queue.push_back(
            {(*revs)[k].t_end, 1, [&sink, revs, k]() { return sink.onRevolution((*revs)[k]); }});
    }
    if (p.merged) {
      auto merged = p.merged;
      queue.push_back({complete, 2, [&sink, merged]() { return sink.onMergedScan(*merged); }});
    }
    if (p.deskewed) {
      auto d = p.deskewed;
      queue.push_back({complete, 3, [&sink, d]() { return sink.onDeskewedScan(*d); }});
    }
    // Later cycles complete no earlier than (c + 2) T + min phase.
    const Status s = flushUntil((c + 2) * period + min_phase);
    if (!s) {
      if (next.valid()) next.wait();
      return Result<SimulationStats>::failure(s.error());
    }
    ++stats.cycles;
    if (progress)
      progress(static_cast<double>(c - first_cycle_ + 1) / std::max<int64_t>(1, num_cycles_));
  }
  const Status s = flushUntil(t_end_ + 1e-9);
  if (!s) return Result<SimulationStats>::failure(s.error());
  for (const Event& e : queue) {
    const Status r = e.emit();
    if (!r) return Result<SimulationStats>::failure(r.error());
  }
  stats.sim_seconds = t_end_ - t_begin_;
  stats.wall_seconds = std::chrono::duration<double>(Clock::now() - wall0).count();
  return stats;
}

}  // namespace sim
}  // namespace gmm_localization
