#include "gmm_localization/ros/ins_adapter.h"

#include <limits>

#include <diagnostic_msgs/DiagnosticStatus.h>

namespace gmm_localization {
namespace node {
namespace {

std::string describe(const InsConvention& c) {
  return std::string("velocity ") + insVelocityFrameName(c.velocity_frame) + ", body axes " +
         insBodyAxesName(c.body_axes) + ", attitude " + insAttitudeName(c.attitude);
}

}  // namespace

InsAdapter::InsAdapter(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& name)
    : nh_(nh),
      pnh_(pnh),
      name_(name),
      // No rate is expected of the INS: only "No events recorded." (and stamps).
      input_rate_(0.0, std::numeric_limits<double>::infinity()),
      adapter_(loadNodeletOptions(pnh, name, loadInsAdapterOptions)),
      problems_(name) {
  const InsAdapterOptions& o = adapter_.options();
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  if (o.publish_tf) tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  pub_ = nh_.advertise<nav_msgs::Odometry>("ins_odom", 50);
  sub_ = nh_.subscribe("driver_odom", static_cast<uint32_t>(o.input_queue_size),
                       &InsAdapter::onOdometry, this, ros::TransportHints().tcpNoDelay());
  setUpDiagnostics();
  ROS_INFO("%s: %s (%s: %s) -> %s in '%s' -> '%s' (%s%s)", name_.c_str(),
           nh_.resolveName("driver_odom").c_str(), o.driver_preset.c_str(),
           describe(o.convention).c_str(), nh_.resolveName("ins_odom").c_str(),
           o.odom_frame.c_str(), o.base_frame.c_str(), insPoseSourceName(o.odometry.pose_source),
           o.publish_tf ? ", publishing TF" : "");
}

InsAdapter::~InsAdapter() {
  sub_.shutdown();
  diagnostics_.reset();  // its task reads members destroyed before it
}

void InsAdapter::onOdometry(const nav_msgs::Odometry::ConstPtr& msg) {
  input_rate_.tick();
  input_rate_.stamp(msg->header.stamp);
  std::lock_guard<std::mutex> lock(mutex_);
  ++received_;
  InsAdapterResult r = adapter_.process(*msg, tf_buffer_);
  last_child_frame_ = r.child_frame;
  switch (r.outcome) {
    case InsAdapterOutcome::kNoTransform:
      ++no_tf_;
      problems_.report("INS odometry dropped: " + r.reason);
      return;
    case InsAdapterOutcome::kInvalid:
      ++invalid_;
      problems_.report("INS odometry dropped: " + r.reason);
      return;
    case InsAdapterOutcome::kOutOfOrder:
      ++out_of_order_;
      problems_.report("INS odometry dropped: " + r.reason);
      return;
    case InsAdapterOutcome::kPublished:
      break;
  }
  if (r.step == InsOdometryStep::kRestarted) {
    ++restarts_;
    problems_.report("INS odometry went back in time: odom restarted at base_link");
  } else if (r.step == InsOdometryStep::kIntegratedOverGap) {
    ++gaps_;
    problems_.report("INS odometry gap of " + std::to_string(r.dt_s) +
                     " s (integrated with the mean twist)");
  }
  ++published_;
  pub_.publish(r.odometry);
  if (tf_broadcaster_) tf_broadcaster_->sendTransform(r.transform);
}

void InsAdapter::setUpDiagnostics() {
  diagnostics_ = std::make_unique<Diagnostics>(nh_, pnh_, name_);
  diagnostics_->add("INS adapter", [this](StatusBuilder& s) {
    using diagnostic_msgs::DiagnosticStatus;
    const InsAdapterOptions& o = adapter_.options();
    std::unique_lock<std::mutex> lock(mutex_);
    s.add("input", nh_.resolveName("driver_odom"));
    s.add("output", nh_.resolveName("ins_odom"));
    s.add("driver preset", o.driver_preset);
    s.add("conventions", describe(o.convention));
    s.add("pose source", insPoseSourceName(o.odometry.pose_source));
    s.add("child frame", last_child_frame_);
    if (const Eigen::Isometry3d* T = adapter_.extrinsic(last_child_frame_)) {
      const Eigen::Vector3d p = T->translation();
      s.add("lever arm in " + o.base_frame + " [m]",
            std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()));
    }
    s.add("messages received", received_);
    s.add("messages published", published_);
    s.add("dropped: no TF", no_tf_);
    s.add("dropped: invalid", invalid_);
    s.add("dropped: out of order", out_of_order_);
    s.add("restarts (time went backwards)", restarts_);
    s.add("gaps", gaps_);
    if (!problems_.last().empty()) s.add("last problem", problems_.last());
    if (received_ == 0) {
      s.summary(DiagnosticStatus::WARN, "no INS odometry received yet");
    } else if (problems_.recent()) {
      s.summary(DiagnosticStatus::WARN, problems_.last());
    }
    lock.unlock();
    input_rate_.fill(s);
  });
}

}  // namespace node
}  // namespace gmm_localization
