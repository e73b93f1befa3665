#include "simulate/simulate_bag_writer.h"

#include <cstring>

#include <nav_msgs/Odometry.h>
#include <ros/message_traits.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

namespace gmm_localization {
namespace tools {
namespace {

#pragma pack(push, 1)
struct CloudPoint {
  float x, y, z, intensity;
  uint16_t ring;
  uint8_t label;
  uint8_t pad;
  float time;
};
#pragma pack(pop)
static_assert(sizeof(CloudPoint) == 24, "cloud point layout");

sensor_msgs::PointCloud2 toCloud(const std::vector<sim::LidarPoint>& pts, const std::string& frame,
                                 ros::Time stamp) {
  sensor_msgs::PointCloud2 c;
  c.header.stamp = stamp;
  c.header.frame_id = frame;
  c.height = 1;
  c.width = static_cast<uint32_t>(pts.size());
  auto field = [&](const char* name, uint32_t offset, uint8_t type) {
    sensor_msgs::PointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = type;
    f.count = 1;
    c.fields.push_back(f);
  };
  field("x", 0, sensor_msgs::PointField::FLOAT32);
  field("y", 4, sensor_msgs::PointField::FLOAT32);
  field("z", 8, sensor_msgs::PointField::FLOAT32);
  field("intensity", 12, sensor_msgs::PointField::FLOAT32);
  field("ring", 16, sensor_msgs::PointField::UINT16);
  field("label", 18, sensor_msgs::PointField::UINT8);
  field("time", 20, sensor_msgs::PointField::FLOAT32);
  c.is_bigendian = false;
  c.point_step = sizeof(CloudPoint);
  c.row_step = c.point_step * c.width;
  c.is_dense = true;
  c.data.resize(static_cast<size_t>(c.row_step));
  auto* out = reinterpret_cast<CloudPoint*>(c.data.data());
  for (size_t i = 0; i < pts.size(); ++i) {
    const sim::LidarPoint& p = pts[i];
    out[i] = {p.x, p.y, p.z, p.intensity, p.ring, p.label, 0, p.time_s};
  }
  return c;
}

geometry_msgs::Transform toTransform(const Eigen::Isometry3d& t) {
  geometry_msgs::Transform m;
  m.translation.x = t.translation().x();
  m.translation.y = t.translation().y();
  m.translation.z = t.translation().z();
  const Eigen::Quaterniond q(t.linear());
  m.rotation.x = q.x();
  m.rotation.y = q.y();
  m.rotation.z = q.z();
  m.rotation.w = q.w();
  return m;
}

geometry_msgs::Pose toPose(const Eigen::Isometry3d& t) {
  const geometry_msgs::Transform tr = toTransform(t);
  geometry_msgs::Pose p;
  p.position.x = tr.translation.x;
  p.position.y = tr.translation.y;
  p.position.z = tr.translation.z;
  p.orientation = tr.rotation;
  return p;
}

void setVector(geometry_msgs::Vector3& v, const Eigen::Vector3d& e) {
  v.x = e.x();
  v.y = e.y();
  v.z = e.z();
}

template <typename Fn>
Status guarded(Fn fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    return Status::failure(std::string("rosbag: ") + e.what());
  }
  return Status::success();
}

}  // namespace

Result<std::unique_ptr<BagSink>> BagSink::open(const BagOptions& options,
                                               const sim::SimulationConfig& config,
                                               double t_begin) {
  std::unique_ptr<BagSink> sink(new BagSink());
  sink->options_ = options;
  sink->config_ = config;
  const Status s = guarded([&]() {
    sink->bag_.open(options.path, rosbag::bagmode::Write);
    sink->bag_.setCompression(options.lz4 ? rosbag::compression::LZ4
                                          : rosbag::compression::Uncompressed);
    sink->bag_.setChunkThreshold(4 * 1024 * 1024);
    sink->open_ = true;
    tf2_msgs::TFMessage tf;
    for (const sim::SensorMount& m : config.rig.sensors) {
      geometry_msgs::TransformStamped t;
      t.header.stamp = sink->stamp(t_begin);
      t.header.frame_id = "base_link";
      t.child_frame_id = m.frame_id;
      t.transform = toTransform(m.base_to_sensor);
      tf.transforms.push_back(t);
    }
    auto header = boost::make_shared<ros::M_string>();
    (*header)["type"] = ros::message_traits::datatype<tf2_msgs::TFMessage>();
    (*header)["md5sum"] = ros::message_traits::md5sum<tf2_msgs::TFMessage>();
    (*header)["message_definition"] = ros::message_traits::definition<tf2_msgs::TFMessage>();
    (*header)["callerid"] = "/gmm_simulate";
    (*header)["latching"] = "1";
    sink->bag_.write("/tf_static", sink->stamp(t_begin), tf, header);
  });
  if (!s) return Result<std::unique_ptr<BagSink>>::failure(s.error() + " (" + options.path + ")");
  return Result<std::unique_ptr<BagSink>>(std::move(sink));
}

BagSink::~BagSink() { close(); }

Status BagSink::close() {
  if (!open_) return Status::success();
  open_ = false;
  return guarded([&]() { bag_.close(); });
}

Status BagSink::onRevolution(const sim::SensorRevolution& rev) {
  if (!options_.per_sensor_clouds) return Status::success();
  const std::string& frame = config_.rig.sensors[rev.sensor].frame_id;
  return guarded([&]() {
    bag_.write("/" + frame + "/velodyne_points", stamp(rev.t_end),
               toCloud(rev.points, frame, stamp(rev.t_start)));
  });
}

Status BagSink::onMergedScan(const sim::MergedScan& scan) {
  if (!options_.merged_cloud) return Status::success();
  return guarded([&]() {
    bag_.write("/velodyne_points", stamp(scan.complete),
               toCloud(scan.points, "base_link", stamp(scan.stamp)));
  });
}

Status BagSink::onGroundTruth(const sim::VehicleState& s) {
  nav_msgs::Odometry o;
  o.header.stamp = stamp(s.t);
  o.header.frame_id = "map";
  o.child_frame_id = "base_link";
  o.pose.pose = toPose(s.pose);
  setVector(o.twist.twist.linear, s.pose.linear().transpose() * s.velocity_world);
  setVector(o.twist.twist.angular, s.angular_velocity_body);
  for (int k = 0; k < 6; ++k) o.pose.covariance[k * 7] = o.twist.covariance[k * 7] = 1e-8;
  return guarded([&]() { bag_.write("/ground_truth/odom", o.header.stamp, o); });
}

Status BagSink::onOdometry(const sim::OdomSample& s) {
  const sim::InsConfig& c = config_.ins;
  nav_msgs::Odometry o;
  o.header.stamp = stamp(s.t);
  o.header.frame_id = "odom";
  o.child_frame_id = "base_link";
  o.pose.pose = toPose(s.pose);
  setVector(o.twist.twist.linear, s.linear_velocity);
  setVector(o.twist.twist.angular, s.angular_velocity);
  const double pos = std::max(1e-6, c.position_noise_m * c.position_noise_m);
  const double att = std::max(1e-8, c.attitude_noise_rad * c.attitude_noise_rad);
  for (int k = 0; k < 3; ++k) {
    o.pose.covariance[k * 7] = pos;
    o.pose.covariance[(k + 3) * 7] = att;
    o.twist.covariance[k * 7] = std::max(1e-6, c.velocity_noise_mps * c.velocity_noise_mps);
    o.twist.covariance[(k + 3) * 7] = std::max(1e-8, c.gyro_noise_rad_s * c.gyro_noise_rad_s);
  }
  tf2_msgs::TFMessage tf;
  geometry_msgs::TransformStamped t;
  t.header = o.header;
  t.child_frame_id = "base_link";
  t.transform = toTransform(s.pose);
  tf.transforms.push_back(t);
  return guarded([&]() {
    bag_.write("/ins/odom", o.header.stamp, o);
    bag_.write("/tf", o.header.stamp, tf);
  });
}

Status BagSink::onImu(const sim::ImuSample& s) {
  const sim::InsConfig& c = config_.ins;
  sensor_msgs::Imu m;
  m.header.stamp = stamp(s.t);
  m.header.frame_id = "base_link";
  m.orientation.x = s.orientation.x();
  m.orientation.y = s.orientation.y();
  m.orientation.z = s.orientation.z();
  m.orientation.w = s.orientation.w();
  setVector(m.angular_velocity, s.angular_velocity);
  setVector(m.linear_acceleration, s.linear_acceleration);
  for (int k = 0; k < 3; ++k) {
    m.orientation_covariance[k * 4] = std::max(1e-8, c.attitude_noise_rad * c.attitude_noise_rad);
    m.angular_velocity_covariance[k * 4] = std::max(
        1e-8, c.gyro_noise_rad_s * c.gyro_noise_rad_s + c.gyro_bias_rad_s * c.gyro_bias_rad_s);
    m.linear_acceleration_covariance[k * 4] = std::max(
        1e-6, c.accel_noise_mps2 * c.accel_noise_mps2 + c.accel_bias_mps2 * c.accel_bias_mps2);
  }
  return guarded([&]() { bag_.write("/imu/data", m.header.stamp, m); });
}

Status BagSink::onGnssFix(const std::string& topic, const sensor_msgs::NavSatFix& fix) {
  return guarded([&]() { bag_.write(topic, fix.header.stamp, fix); });
}

}  // namespace tools
}  // namespace gmm_localization
