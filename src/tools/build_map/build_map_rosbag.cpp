// build_map input: PointCloud2 scans and their poses from a rosbag.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "build_map/build_map_readers.h"
#include "gmm_localization/ros/cloud_conversion.h"

namespace gmm_localization {
namespace tools {
namespace {

Eigen::Isometry3d toIsometry(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  Eigen::Quaterniond q(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
  t.linear() =
      (q.norm() > 1e-9 ? q.normalized() : Eigen::Quaterniond::Identity()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return t;
}

Eigen::Isometry3d toIsometry(const geometry_msgs::Transform& p) {
  geometry_msgs::Pose pose;
  pose.position.x = p.translation.x;
  pose.position.y = p.translation.y;
  pose.position.z = p.translation.z;
  pose.orientation = p.rotation;
  return toIsometry(pose);
}

struct StampedPose {
  double t;
  Eigen::Isometry3d pose;
};

/// The transforms of every tf2_msgs/TFMessage on `topic`.
std::vector<geometry_msgs::TransformStamped> readTf(rosbag::Bag& bag, const std::string& topic) {
  std::vector<geometry_msgs::TransformStamped> out;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& msg : view) {
    if (auto tf = msg.instantiate<tf2_msgs::TFMessage>()) {
      out.insert(out.end(), tf->transforms.begin(), tf->transforms.end());
    }
  }
  return out;
}

/// The frames from `frame` up to its root (or to `stop`), `frame` first.
std::set<std::string> ancestors(const std::string& frame, const std::string& stop,
                                const std::map<std::string, std::string>& parent_of) {
  std::set<std::string> out;
  for (std::string f = frame; out.insert(f).second && f != stop;) {
    auto p = parent_of.find(f);
    if (p == parent_of.end()) break;
    f = p->second;
  }
  return out;
}

/// Poses of `child` in `parent` from the bag's /tf (and /tf_static), composed through the TF
/// tree: looked up at every stamp of a dynamic transform on the chain between the two frames
/// (interpolated by tf2 between the stamps of the other edges). Fails naming the frames and
/// listing the bag's dynamic edges when none can be looked up.
Result<std::vector<StampedPose>> posesFromTf(const std::vector<geometry_msgs::TransformStamped>& tf,
                                             const std::vector<geometry_msgs::TransformStamped>& st,
                                             const std::string& parent, const std::string& child) {
  using R = Result<std::vector<StampedPose>>;
  double t0 = 0.0, t1 = 0.0;
  for (size_t i = 0; i < tf.size(); ++i) {
    const double t = tf[i].header.stamp.toSec();
    t0 = i == 0 ? t : std::min(t0, t);
    t1 = i == 0 ? t : std::max(t1, t);
  }
  // Every transform kept for the whole bag.
  tf2::BufferCore buffer(ros::Duration(t1 - t0 + 10.0));
  std::map<std::string, std::string> parent_of;
  for (const auto& t : st) {
    buffer.setTransform(t, "bag", true);
    parent_of[t.child_frame_id] = t.header.frame_id;
  }
  std::set<std::pair<std::string, std::string>> edges;
  for (const auto& t : tf) {
    buffer.setTransform(t, "bag", false);
    parent_of[t.child_frame_id] = t.header.frame_id;
    edges.insert({t.header.frame_id, t.child_frame_id});
  }
  std::set<std::string> chain = ancestors(child, parent, parent_of);
  const std::set<std::string> up = ancestors(parent, child, parent_of);
  chain.insert(up.begin(), up.end());
  std::set<ros::Time> stamps;
  for (const auto& t : tf) {
    if (chain.count(t.child_frame_id)) stamps.insert(t.header.stamp);
  }
  std::vector<StampedPose> poses;
  std::string last_error;
  for (const ros::Time& t : stamps) {
    try {
      const auto p = buffer.lookupTransform(parent, child, t);
      poses.push_back({t.toSec(), toIsometry(p.transform)});
    } catch (const tf2::TransformException& e) {
      last_error = e.what();
    }
  }
  if (poses.empty()) {
    std::string have;
    size_t listed = 0;
    for (const auto& [p, c] : edges) {
      if (listed++ == 8) {
        have += ", ...";
        break;
      }
      have += (have.empty() ? "" : ", ") + p + " -> " + c;
    }
    return R::failure("no transform " + parent + " -> " + child + " in /tf" +
                      (last_error.empty() ? "" : " (" + last_error + ")") +
                      "; its edges: " + (have.empty() ? "none" : have));
  }
  return R(std::move(poses));
}

}  // namespace

struct RosbagSource::Impl {
  RosbagSourceOptions o;
  rosbag::Bag bag;
  std::unique_ptr<rosbag::View> clouds;
  rosbag::View::iterator it;
  std::vector<StampedPose> poses;
  std::string child_frame;                             // empty: the pose type has none
  std::unique_ptr<tf2::BufferCore> tf_static;          // /tf_static, for the extrinsics
  std::map<std::string, Eigen::Isometry3d> extrinsic;  // per cloud frame
  size_t total = 0, index = 0;
  size_t skipped_every = 0, skipped_no_pose = 0, skipped_gap = 0, skipped_malformed = 0;
  size_t deskewed = 0, no_times = 0, refused_times = 0;
  std::string last_malformed, last_refused;
  std::set<std::string> time_sources;  // how the deskewed clouds' times were read

  bool interpolate(double t, Eigen::Isometry3d& out, bool& gap) const {
    gap = false;
    if (poses.empty() || t < poses.front().t || t > poses.back().t) return false;
    auto hi = std::lower_bound(poses.begin(), poses.end(), t,
                               [](const StampedPose& p, double v) { return p.t < v; });
    if (hi->t == t) {
      out = hi->pose;
      return true;
    }
    auto lo = hi - 1;
    if (hi->t - lo->t > o.max_pose_gap_s) {
      gap = true;
      return false;
    }
    const double a = (t - lo->t) / (hi->t - lo->t);
    const Eigen::Quaterniond q0(lo->pose.linear()), q1(hi->pose.linear());
    out = Eigen::Isometry3d::Identity();
    out.linear() = q0.slerp(a, q1).toRotationMatrix();
    out.translation() = (1.0 - a) * lo->pose.translation() + a * hi->pose.translation();
    return true;
  }

  /// Moves every point with the pose at its own time (stamp + time), interpolated once per
  /// millisecond bucket; false (and `gap` as in interpolate) when a pose is missing.
  bool deskew(double stamp, const std::vector<Eigen::Vector3f>& points,
              const std::vector<float>& times, const Eigen::Isometry3d& pose_T_cloud,
              PointBatch& batch, bool& gap) const {
    std::map<long, Eigen::Isometry3d> bucket;
    batch.points_m.resize(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      const long ms = std::isfinite(times[i]) ? std::lround(times[i] * 1000.0) : 0;
      auto it = bucket.find(ms);
      if (it == bucket.end()) {
        Eigen::Isometry3d pose;
        if (!interpolate(stamp + ms * 1e-3, pose, gap)) return false;
        it = bucket.emplace(ms, o.map_T_world * pose * pose_T_cloud).first;
      }
      batch.points_m[i] = (it->second * points[i].cast<double>()).cast<float>();
    }
    return true;
  }
};

RosbagSource::~RosbagSource() = default;

Result<std::unique_ptr<RosbagSource>> RosbagSource::open(const RosbagSourceOptions& o) {
  using R = Result<std::unique_ptr<RosbagSource>>;
  auto src = std::unique_ptr<RosbagSource>(new RosbagSource());
  src->impl_ = std::make_unique<Impl>();
  Impl& m = *src->impl_;
  m.o = o;
  const std::string where = "bag '" + o.path + "'";
  try {
    m.bag.open(o.path, rosbag::bagmode::Read);
    const std::vector<geometry_msgs::TransformStamped> tf_static = readTf(m.bag, "/tf_static");
    m.tf_static = std::make_unique<tf2::BufferCore>();
    for (const auto& t : tf_static) m.tf_static->setTransform(t, "bag", true);
    if (!o.pose_tf_child.empty()) {
      auto poses = posesFromTf(readTf(m.bag, "/tf"), tf_static, o.pose_tf_parent, o.pose_tf_child);
      if (!poses) return R::failure(where + ": " + poses.error());
      m.poses = std::move(*poses);
      m.child_frame = o.pose_tf_child;
    } else {
      rosbag::View pose_view(m.bag, rosbag::TopicQuery(o.pose_topic));
      for (const rosbag::MessageInstance& msg : pose_view) {
        if (auto odom = msg.instantiate<nav_msgs::Odometry>()) {
          m.poses.push_back({odom->header.stamp.toSec(), toIsometry(odom->pose.pose)});
          m.child_frame = odom->child_frame_id;
        } else if (auto ps = msg.instantiate<geometry_msgs::PoseStamped>()) {
          m.poses.push_back({ps->header.stamp.toSec(), toIsometry(ps->pose)});
        } else if (auto pc = msg.instantiate<geometry_msgs::PoseWithCovarianceStamped>()) {
          m.poses.push_back({pc->header.stamp.toSec(), toIsometry(pc->pose.pose)});
        } else {
          return R::failure(where + ": pose topic '" + o.pose_topic + "' carries " +
                            msg.getDataType() +
                            ", not Odometry, PoseStamped or PoseWithCovarianceStamped");
        }
      }
      if (m.poses.empty()) {
        std::string hint;
        if (rosbag::View(m.bag, rosbag::TopicQuery("/tf")).size() > 0) {
          hint = " (the bag has /tf: --pose-tf PARENT,CHILD takes the poses from it)";
        }
        return R::failure(where + ": no message on pose topic '" + o.pose_topic + "'" + hint);
      }
    }
    std::stable_sort(m.poses.begin(), m.poses.end(),
                     [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; });
    m.poses.erase(
        std::unique(m.poses.begin(), m.poses.end(),
                    [](const StampedPose& a, const StampedPose& b) { return a.t == b.t; }),
        m.poses.end());
    m.clouds = std::make_unique<rosbag::View>(m.bag, rosbag::TopicQuery(o.cloud_topic));
    m.total = m.clouds->size();
    if (m.total == 0)
      return R::failure(where + ": no message on cloud topic '" + o.cloud_topic + "'");
    m.it = m.clouds->begin();
  } catch (const std::exception& e) {
    return R::failure(where + ": " + e.what());
  }
  return R(std::move(src));
}

Result<bool> RosbagSource::next(PointBatch& batch) {
  using R = Result<bool>;
  Impl& m = *impl_;
  batch.clear();
  try {
    for (; m.it != m.clouds->end(); ++m.it) {
      const rosbag::MessageInstance& msg = *m.it;
      if (m.index++ % static_cast<size_t>(m.o.every) != 0) {
        ++m.skipped_every;
        continue;
      }
      auto cloud = msg.instantiate<sensor_msgs::PointCloud2>();
      if (!cloud) {
        return R::failure("bag '" + m.o.path + "': cloud topic '" + m.o.cloud_topic + "' carries " +
                          msg.getDataType() + ", not sensor_msgs/PointCloud2");
      }
      const double stamp = cloud->header.stamp.toSec();
      Eigen::Isometry3d pose;
      bool gap = false;
      if (!m.interpolate(stamp, pose, gap)) {
        ++(gap ? m.skipped_gap : m.skipped_no_pose);
        continue;
      }
      // The matcher's reader (cloud_conversion.h): x, y, z and the per-point times of any
      // driver it knows, converted to seconds after the stamp.
      auto data = node::fromMsg(*cloud, m.o.time_field);
      if (!data) {
        ++m.skipped_malformed;
        m.last_malformed = data.error();
        continue;
      }
      const std::vector<Eigen::Vector3f>& points = data->points;
      std::vector<float> times;
      if (m.o.deskew) {
        times = std::move(data->time_s);
        if (!data->time_problem.empty()) {
          ++m.refused_times;
          m.last_refused = data->time_problem;
        } else if (times.empty()) {
          ++m.no_times;
        }
      }
      const std::string& frame = cloud->header.frame_id;
      auto ext = m.extrinsic.find(frame);
      if (ext == m.extrinsic.end()) {
        Eigen::Isometry3d e = Eigen::Isometry3d::Identity();
        if (m.o.has_extrinsic) {
          e = m.o.pose_T_cloud;
        } else if (!m.child_frame.empty() && frame != m.child_frame) {
          // The chain of /tf_static edges between the two frames, in either direction.
          try {
            e = toIsometry(
                m.tf_static->lookupTransform(m.child_frame, frame, ros::Time(0)).transform);
          } catch (const tf2::TransformException& ex) {
            return R::failure("bag '" + m.o.path + "': the clouds are in frame '" + frame +
                              "' but the poses are of frame '" + m.child_frame +
                              "', and /tf_static has no chain of transforms between them (" +
                              ex.what() + "): pass --extrinsic");
          }
        }
        ext = m.extrinsic.emplace(frame, e).first;
      }
      if (times.empty()) {
        setBatchFromSensorFrame(points, m.o.map_T_world * pose * ext->second, batch);
      } else if (!m.deskew(stamp, points, times, ext->second, batch, gap)) {
        ++(gap ? m.skipped_gap : m.skipped_no_pose);
        batch.clear();
        continue;
      } else {
        ++m.deskewed;
        m.time_sources.insert(node::describePointTimes(*data));
      }
      batch.has_sensor_origin = true;
      batch.sensor_origin_m = (m.o.map_T_world * pose * ext->second).translation();
      // The poses' frame (e.g. base_link) at the stamp is the vehicle frame of the reflectivity
      // layer's ground returns, as in the matcher, which levels each scan in base_link.
      batch.has_vehicle_origin = true;
      batch.vehicle_origin_m = (m.o.map_T_world * pose).translation();
      if (data->intensity.size() == points.size()) batch.intensity = std::move(data->intensity);
      ++m.it;
      return true;
    }
  } catch (const std::exception& e) {
    return R::failure("bag '" + m.o.path + "': " + e.what());
  }
  return false;
}

size_t RosbagSource::sizeHint() const { return impl_->total; }

std::string RosbagSource::describe() const {
  const Impl& m = *impl_;
  const std::string poses = m.o.pose_tf_child.empty() ? "on '" + m.o.pose_topic + "'"
                                                      : "of " + m.o.pose_tf_parent + " -> " +
                                                            m.o.pose_tf_child + " from /tf";
  return "rosbag '" + m.o.path + "' (" + std::to_string(m.total) + " clouds on '" +
         m.o.cloud_topic + "', " + std::to_string(m.poses.size()) + " poses " + poses + ")";
}

std::string RosbagSource::skipped() const {
  const Impl& m = *impl_;
  std::string sources;
  for (const std::string& t : m.time_sources) sources += (sources.empty() ? "" : ", ") + t;
  std::string s = std::to_string(m.deskewed) + " deskewed" +
                  (sources.empty() ? "" : " (per-point " + sources + ")") + ", " +
                  std::to_string(m.no_times) + " without per-point times, " +
                  std::to_string(m.refused_times) + " with times that make no sense" +
                  (m.last_refused.empty() ? "" : " (last: " + m.last_refused + ")") +
                  "; skipped: " + std::to_string(m.skipped_no_pose) +
                  " outside the poses' time span, " + std::to_string(m.skipped_gap) +
                  " across a pose gap, " + std::to_string(m.skipped_malformed) + " malformed" +
                  (m.last_malformed.empty() ? "" : " (last: " + m.last_malformed + ")") + ", " +
                  std::to_string(m.skipped_every) + " by --every";
  return s;
}

}  // namespace tools
}  // namespace gmm_localization
