// build_map input: PointCloud2 scans and their poses from a rosbag.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "build_map/build_map_readers.h"

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

double readFloat(const uint8_t* p, int type) {
  if (type == sensor_msgs::PointField::FLOAT32) {
    float f;
    std::memcpy(&f, p, 4);
    return f;
  }
  double d;
  std::memcpy(&d, p, 8);
  return d;
}

/// Reads x, y, z (and, when `time_field` is non-empty and present, the per-point time [s]) of
/// every point; returns an empty string on success, else what is malformed. `times` is left
/// empty when the cloud has no such field.
std::string readPoints(const sensor_msgs::PointCloud2& c, const std::string& time_field,
                       std::vector<Eigen::Vector3f>& out, std::vector<float>& times) {
  out.clear();
  times.clear();
  int offset[4] = {-1, -1, -1, -1}, type[4] = {0, 0, 0, 0};
  const std::string names[4] = {"x", "y", "z", time_field};
  for (const auto& f : c.fields) {
    for (int k = 0; k < 4; ++k) {
      if (!names[k].empty() && f.name == names[k]) {
        offset[k] = static_cast<int>(f.offset);
        type[k] = f.datatype;
      }
    }
  }
  const int fields = offset[3] >= 0 ? 4 : 3;
  for (int k = 0; k < fields; ++k) {
    if (offset[k] < 0) return "no field '" + names[k] + "'";
    if (type[k] != sensor_msgs::PointField::FLOAT32 &&
        type[k] != sensor_msgs::PointField::FLOAT64) {
      return "field '" + names[k] + "' is not FLOAT32/FLOAT64";
    }
    const int size = type[k] == sensor_msgs::PointField::FLOAT32 ? 4 : 8;
    if (static_cast<uint64_t>(offset[k]) + size > c.point_step) return "point_step too small";
  }
  if (c.is_bigendian) return "big-endian data";
  if (uint64_t{c.width} * c.point_step > c.row_step) return "row_step < width * point_step";
  if (uint64_t{c.row_step} * c.height > c.data.size()) return "data shorter than row_step * height";
  out.reserve(uint64_t{c.width} * c.height);
  for (uint32_t r = 0; r < c.height; ++r) {
    const uint8_t* row = c.data.data() + uint64_t{r} * c.row_step;
    for (uint32_t i = 0; i < c.width; ++i) {
      const uint8_t* p = row + uint64_t{i} * c.point_step;
      out.emplace_back(static_cast<float>(readFloat(p + offset[0], type[0])),
                       static_cast<float>(readFloat(p + offset[1], type[1])),
                       static_cast<float>(readFloat(p + offset[2], type[2])));
      if (fields == 4) times.push_back(static_cast<float>(readFloat(p + offset[3], type[3])));
    }
  }
  return {};
}

}  // namespace

struct RosbagSource::Impl {
  RosbagSourceOptions o;
  rosbag::Bag bag;
  std::unique_ptr<rosbag::View> clouds;
  rosbag::View::iterator it;
  struct StampedPose {
    double t;
    Eigen::Isometry3d pose;
  };
  std::vector<StampedPose> poses;
  std::string child_frame;  // empty: the pose type has none
  std::map<std::pair<std::string, std::string>, Eigen::Isometry3d> tf_static;  // parent_T_child
  std::map<std::string, Eigen::Isometry3d> extrinsic;                          // per cloud frame
  size_t total = 0, index = 0;
  size_t skipped_every = 0, skipped_no_pose = 0, skipped_gap = 0, skipped_malformed = 0;
  size_t deskewed = 0;
  std::string last_malformed;

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
    if (m.poses.empty())
      return R::failure(where + ": no message on pose topic '" + o.pose_topic + "'");
    std::stable_sort(
        m.poses.begin(), m.poses.end(),
        [](const Impl::StampedPose& a, const Impl::StampedPose& b) { return a.t < b.t; });
    m.poses.erase(std::unique(m.poses.begin(), m.poses.end(),
                              [](const Impl::StampedPose& a, const Impl::StampedPose& b) {
                                return a.t == b.t;
                              }),
                  m.poses.end());
    rosbag::View tf_view(m.bag, rosbag::TopicQuery("/tf_static"));
    for (const rosbag::MessageInstance& msg : tf_view) {
      if (auto tf = msg.instantiate<tf2_msgs::TFMessage>()) {
        for (const auto& t : tf->transforms) {
          m.tf_static[{t.header.frame_id, t.child_frame_id}] = toIsometry(t.transform);
        }
      }
    }
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
  std::vector<Eigen::Vector3f> points;
  std::vector<float> times;
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
      const std::string malformed =
          readPoints(*cloud, m.o.deskew ? m.o.time_field : std::string(), points, times);
      if (!malformed.empty()) {
        ++m.skipped_malformed;
        m.last_malformed = malformed;
        continue;
      }
      const std::string& frame = cloud->header.frame_id;
      auto ext = m.extrinsic.find(frame);
      if (ext == m.extrinsic.end()) {
        Eigen::Isometry3d e = Eigen::Isometry3d::Identity();
        if (m.o.has_extrinsic) {
          e = m.o.pose_T_cloud;
        } else if (!m.child_frame.empty() && frame != m.child_frame) {
          auto direct = m.tf_static.find({m.child_frame, frame});
          auto reverse = m.tf_static.find({frame, m.child_frame});
          if (direct != m.tf_static.end()) {
            e = direct->second;
          } else if (reverse != m.tf_static.end()) {
            e = reverse->second.inverse();
          } else {
            return R::failure("bag '" + m.o.path + "': the clouds are in frame '" + frame +
                              "' but the poses are of frame '" + m.child_frame +
                              "', and /tf_static has no edge between them: pass --extrinsic");
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
      }
      batch.has_sensor_origin = true;
      batch.sensor_origin_m = (m.o.map_T_world * pose * ext->second).translation();
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
  return "rosbag '" + impl_->o.path + "' (" + std::to_string(impl_->total) + " clouds on '" +
         impl_->o.cloud_topic + "', " + std::to_string(impl_->poses.size()) + " poses on '" +
         impl_->o.pose_topic + "')";
}

std::string RosbagSource::skipped() const {
  const Impl& m = *impl_;
  std::string s = std::to_string(m.deskewed) + " deskewed with per-point '" + m.o.time_field +
                  "'; skipped: " + std::to_string(m.skipped_no_pose) +
                  " outside the poses' time span, " + std::to_string(m.skipped_gap) +
                  " across a pose gap, " + std::to_string(m.skipped_malformed) + " malformed" +
                  (m.last_malformed.empty() ? "" : " (last: " + m.last_malformed + ")") + ", " +
                  std::to_string(m.skipped_every) + " by --every";
  return s;
}

}  // namespace tools
}  // namespace gmm_localization
