#include "gmm_localization/ros/gnss_initializer.h"

#include <cmath>
#include <limits>

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

#include "gmm_localization/ros/gnss_conversion.h"
#include "gmm_localization/ros/map_server_client.h"

namespace gmm_localization {
namespace node {
namespace {

/// What the user can do about a refusal.
std::string withHint(const std::string& reason) {
  if (reason.find("georeference") != std::string::npos) {
    return reason +
           ": rebuild the map with build_map --utm-zone ZONE (or --epsg CODE / --mgrs-origin REF) "
           "so that GNSS positions can be placed in it";
  }
  if (reason.find("from the map origin") != std::string::npos) {
    return reason + ": is this the map of the area the vehicle is in?";
  }
  if (reason.find("too coarse") != std::string::npos) {
    return reason + " (wait for a better solution or raise max_horizontal_sigma_m)";
  }
  if (reason.find("waiting for a heading") != std::string::npos) {
    return reason + "; drive straight ahead, or set heading_topic to an ENU attitude source";
  }
  return reason;
}

}  // namespace

const char* GnssInitializer::stateName(State s) {
  switch (s) {
    case State::kWaiting:
      return "waiting for a usable fix";
    case State::kSent:
      return "pose sent, waiting for an accepted match";
    case State::kLocalized:
      return "localized (idle)";
    case State::kGaveUp:
      return "gave up (max_attempts)";
  }
  return "?";
}

GnssInitializer::GnssInitializer(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name)
    : nh_(nh),
      pnh_(pnh),
      name_(name),
      options_(loadNodeletOptions(pnh, name, loadGnssInitializerOptions)),
      fix_rate_(0.0, std::numeric_limits<double>::infinity()),
      initial_pose_(options_.pose),
      problems_(name) {
  start_wall_s_ = wallNow();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  pose_pub_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("initialpose", 2);
  fix_sub_ = nh_.subscribe("fix", 20, &GnssInitializer::onFix, this);
  if (!options_.heading_topic.empty()) {
    heading_sub_ = nh_.subscribe(options_.heading_topic, 50, &GnssInitializer::onHeading, this);
  }
  index_sub_ = nh_.subscribe("map_index", 4, &GnssInitializer::onIndex, this);
  status_sub_ = nh_.subscribe("status", 20, &GnssInitializer::onStatus, this);
  timer_ = nh_.createWallTimer(ros::WallDuration(1.0), &GnssInitializer::onTimer, this);
  setUpDiagnostics();
  ROS_INFO("%s: first pose from %s (heading: %s) in the map's georeference -> %s", name_.c_str(),
           nh_.resolveName("fix").c_str(),
           options_.heading_topic.empty() ? "course over ground"
                                          : nh_.resolveName(options_.heading_topic).c_str(),
           nh_.resolveName("initialpose").c_str());
}

GnssInitializer::~GnssInitializer() {
  timer_.stop();
  fix_sub_.shutdown();
  heading_sub_.shutdown();
  diagnostics_.reset();  // its task reads members destroyed before it
}

bool GnssInitializer::leverArm(const std::string& antenna_frame, Eigen::Vector3d& out) {
  out.setZero();
  if (!options_.lever_arm_from_tf || antenna_frame.empty() ||
      antenna_frame == options_.base_frame) {
    return true;
  }
  try {
    const auto t = tf_buffer_.lookupTransform(options_.base_frame, antenna_frame, ros::Time(0));
    out = Eigen::Vector3d(t.transform.translation.x, t.transform.translation.y,
                          t.transform.translation.z);
    return out.allFinite();
  } catch (const tf2::TransformException& e) {
    problems_.report("fix not used: no TF " + options_.base_frame + " <- " + antenna_frame +
                     " (the antenna's lever arm): publish it as a static transform, or set " +
                     pnh_.resolveName("lever_arm_from_tf") + " false (" + e.what() + ")");
    return false;
  }
}

void GnssInitializer::onHeading(const sensor_msgs::Imu::ConstPtr& msg) {
  double mount_yaw = 0.0;
  if (!msg->header.frame_id.empty() && msg->header.frame_id != options_.base_frame) {
    try {
      const auto t =
          tf_buffer_.lookupTransform(msg->header.frame_id, options_.base_frame, ros::Time(0));
      tf2::Quaternion q;
      tf2::fromMsg(t.transform.rotation, q);
      double roll, pitch;
      tf2::Matrix3x3(q).getRPY(roll, pitch, mount_yaw);
    } catch (const tf2::TransformException& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      ++headings_refused_;
      problems_.report("heading not used: no TF " + msg->header.frame_id + " <- " +
                       options_.base_frame + " (" + e.what() + ")");
      return;
    }
  }
  auto h = gnssHeadingFromMsg(*msg, mount_yaw);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!h || !initial_pose_.addHeading(*h)) {
    ++headings_refused_;
    problems_.report("heading on " + nh_.resolveName(options_.heading_topic) +
                     " not used: " + (h ? std::string("not finite") : h.error()));
    return;
  }
  ++headings_;
}

void GnssInitializer::onIndex(const MapIndex::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  const Georeference g = georeferenceOf(*msg);
  if (!have_index_ || msg->map_directory != map_directory_) {
    initial_pose_.reset();
    if (!g.hasGrid()) {
      problems_.report(withHint(
          "map '" + msg->map_directory + "': " +
          (g.present ? "its georeference names no UTM zone" : "the map has no georeference")));
    } else {
      ROS_INFO("%s: map '%s' georeference %s", name_.c_str(), msg->map_directory.c_str(),
               g.describe().c_str());
    }
  }
  have_index_ = true;
  georeference_ = g;
  map_directory_ = msg->map_directory;
}

void GnssInitializer::onStatus(const MatchStatus::ConstPtr& msg) {
  if (!msg->accepted) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (state_ == State::kLocalized) return;
  ROS_INFO("%s: %s; the GNSS initializer is idle", name_.c_str(),
           state_ == State::kSent ? "the matcher accepted a match after the GNSS pose"
                                  : "the matcher is localized without the GNSS pose");
  state_ = State::kLocalized;
}

void GnssInitializer::onFix(const sensor_msgs::NavSatFix::ConstPtr& msg) {
  fix_rate_.tick();
  fix_rate_.stamp(msg->header.stamp);
  std::lock_guard<std::mutex> lock(mutex_);
  ++fixes_;
  last_fix_wall_s_ = wallNow();
  const ros::Time now = ros::Time::now();
  // A pose sent before the clock ran (use_sim_time, no /clock yet) waits retry_s from the
  // clock's start, not from 0.
  if (state_ == State::kSent && sent_at_.isZero()) sent_at_ = now;
  if (state_ == State::kSent && (now - sent_at_).toSec() > options_.retry_s) {
    if (options_.max_attempts > 0 && attempts_ >= options_.max_attempts) {
      state_ = State::kGaveUp;
      problems_.report(
          "no match accepted after " + std::to_string(attempts_) +
          " GNSS poses: giving up (max_attempts); give a pose in rviz or check the map");
    } else {
      state_ = State::kWaiting;
      problems_.report("no match accepted within retry_s of the GNSS pose: sending a newer one");
    }
  }
  if (state_ != State::kWaiting) return;
  if (!have_index_) {
    ++refused_;
    last_refusal_ =
        "no map index yet on " + nh_.resolveName("map_index") + " (is the map server running?)";
    problems_.report("fix not used: " + last_refusal_);
    return;
  }
  Eigen::Vector3d lever;
  if (!leverArm(msg->header.frame_id, lever)) {
    ++refused_;
    last_refusal_ = "no lever arm (TF)";
    return;
  }
  initial_pose_.setLeverArm(lever);
  auto e = initial_pose_.addFix(georeference_, gnssFixFromMsg(*msg));
  if (!e) {
    ++refused_;
    last_refusal_ = withHint(e.error());
    problems_.report("fix not used: " + last_refusal_);
    return;
  }
  pose_pub_.publish(initialPoseMsg(*e, options_.map_frame));
  state_ = State::kSent;
  sent_at_ = ros::Time::now();
  ++attempts_;
  char text[200];
  std::snprintf(text, sizeof text, "x %.2f y %.2f yaw %.3f (sigma %.2f m, %.1f deg; %s)", e->x_m,
                e->y_m, e->yaw_rad, std::sqrt(0.5 * e->cov_xy_yaw.topLeftCorner<2, 2>().trace()),
                std::sqrt(e->cov_xy_yaw(2, 2)) * 180.0 / M_PI, e->heading_source.c_str());
  last_sent_ = text;
  ROS_INFO("%s: initial pose from GNSS #%d: %s", name_.c_str(), attempts_, text);
}

void GnssInitializer::onTimer(const ros::WallTimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (state_ != State::kWaiting && state_ != State::kSent) return;
  const bool heard = last_fix_wall_s_ >= 0.0;
  const double silent = wallNow() - (heard ? last_fix_wall_s_ : start_wall_s_);
  if (silent > options_.fix_timeout_s) {
    problems_.report("no NavSatFix on " + nh_.resolveName("fix") + " " +
                     silenceText(heard, silent) +
                     ": check the launch argument gnss_fix_topic and the receiver driver");
  }
}

void GnssInitializer::setUpDiagnostics() {
  diagnostics_ = std::make_unique<Diagnostics>(nh_, pnh_, name_);
  diagnostics_->add("GNSS initializer", [this](StatusBuilder& s) {
    using diagnostic_msgs::DiagnosticStatus;
    std::unique_lock<std::mutex> lock(mutex_);
    s.add("state", stateName(state_));
    s.add("fix topic", nh_.resolveName("fix"));
    s.add("heading", options_.heading_topic.empty() ? std::string("course over ground")
                                                    : nh_.resolveName(options_.heading_topic));
    s.add("map georeference", have_index_ ? georeference_.describe() : "no map index yet");
    s.add("fixes received", fixes_);
    s.add("fixes not used", refused_);
    s.add("headings used", headings_);
    s.add("headings refused", headings_refused_);
    s.add("poses sent", attempts_);
    if (!last_sent_.empty()) s.add("last pose sent", last_sent_);
    if (!last_refusal_.empty()) s.add("last refusal", last_refusal_);
    if (state_ == State::kGaveUp) {
      s.summary(DiagnosticStatus::ERROR, stateName(state_));
    } else if ((state_ == State::kWaiting || state_ == State::kSent) && problems_.recent()) {
      s.summary(DiagnosticStatus::WARN, problems_.last());
    } else {
      s.summary(DiagnosticStatus::OK, stateName(state_));
    }
    lock.unlock();
    fix_rate_.fill(s);
  });
}

}  // namespace node
}  // namespace gmm_localization
