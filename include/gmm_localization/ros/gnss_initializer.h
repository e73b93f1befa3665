#pragma once
// The GNSS initializer: gives the stack its first pose from a GNSS receiver, so a vehicle starts
// without rviz's "2D Pose Estimate" (launch/localization.launch gnss_initializer:=true).
//
// Topics (relative; remap in launch):
//   fix          sensor_msgs/NavSatFix in: the receiver's fixes (header.frame_id: the antenna
//                frame, whose lever arm to base_link comes from TF).
//   <heading_topic> sensor_msgs/Imu in (optional, parameter): ENU orientation of the vehicle (a
//                dual-antenna receiver or the INS); without it the course over ground is used.
//   map_index    gmm_localization/MapIndex in: the map's georeference (build_map --utm-zone/
//                --epsg/--mgrs-origin).
//   status       gmm_localization/MatchStatus in: the matcher's; an accepted match after a pose
//                was sent ends the initializer's work.
//   initialpose  geometry_msgs/PoseWithCovarianceStamped out (remapped to /initialpose): the
//                pose (GnssInitialPose, core/localization/gnss_initial_pose.h) with the fix's
//                covariance, which sizes the matcher's first search window.
// A pose is sent from the first usable fix; when no match is accepted within retry_s it is sent
// again from a newer fix (up to max_attempts). Once a match is accepted the node stays idle
// (a later relocalization is the matcher's and the EKF's business). Every refusal (no
// georeference, no fix, a coarse fix, a fix outside the map's reach, no heading yet, a missing
// TF) is a throttled WARN naming the cause and the fix, and the diagnostic "<name>: GNSS
// initializer".

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "gmm_localization/MapIndex.h"
#include "gmm_localization/MatchStatus.h"
#include "gmm_localization/core/localization/gnss_initial_pose.h"
#include "gmm_localization/ros/diagnostics.h"
#include "gmm_localization/ros/gnss_initializer_options.h"

namespace gmm_localization {
namespace node {

class GnssInitializer {
 public:
  /// Throws ConfigError on a bad parameter.
  GnssInitializer(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name);
  ~GnssInitializer();
  GnssInitializer(const GnssInitializer&) = delete;
  GnssInitializer& operator=(const GnssInitializer&) = delete;

  enum class State { kWaiting, kSent, kLocalized, kGaveUp };
  static const char* stateName(State s);

 private:
  void onFix(const sensor_msgs::NavSatFix::ConstPtr& msg);
  void onHeading(const sensor_msgs::Imu::ConstPtr& msg);
  void onIndex(const MapIndex::ConstPtr& msg);
  void onStatus(const MatchStatus::ConstPtr& msg);
  void onTimer(const ros::WallTimerEvent&);
  /// The antenna's lever arm in base_link from TF; false (with a problem) when it is missing.
  bool leverArm(const std::string& antenna_frame, Eigen::Vector3d& out);
  void setUpDiagnostics();

  ros::NodeHandle nh_, pnh_;
  std::string name_;
  GnssInitializerOptions options_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  ros::Subscriber fix_sub_, heading_sub_, index_sub_, status_sub_;
  ros::Publisher pose_pub_;
  ros::WallTimer timer_;
  FrequencyMonitor fix_rate_;
  std::unique_ptr<Diagnostics> diagnostics_;

  std::mutex mutex_;  // guards everything below
  GnssInitialPose initial_pose_;
  bool have_index_ = false;
  Georeference georeference_;
  std::string map_directory_;
  State state_ = State::kWaiting;
  ros::Time sent_at_;
  int attempts_ = 0;
  uint64_t fixes_ = 0, refused_ = 0, headings_ = 0, headings_refused_ = 0;
  std::string last_refusal_;
  std::string last_sent_;
  double last_fix_wall_s_ = -1.0;
  double start_wall_s_ = 0.0;
  ProblemLog problems_;  ///< its latest problem (WARN throttled)
};

}  // namespace node
}  // namespace gmm_localization
