// The matcher nodelet's session, built as the nodelet builds it (makeMatcherSession, from
// MatcherOptions loaded by the real loader from the shipped config/matcher.yaml), driven without
// a master: the shipped scan queue (scan_queue_size 3) drops the oldest of the received clouds,
// the shipped time_backwards_tolerance_s resets the session, the configured initial pose is
// re-armed (initial_pose/on_reset), and `evaluate`'s pipeline options carry the same session.

#include "gmm_localization/ros/matcher.h"

#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "gmm_localization/ros/ekf_node_options.h"
#include "gmm_localization/ros/matcher_options.h"
#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {
namespace {

/// The repository root, from this file's path (the tests run from any directory).
std::string repositoryRoot() {
  const std::string here = __FILE__;
  const std::string tail = "test/ros/matcher_session_test.cpp";
  if (here.size() > tail.size() &&
      here.compare(here.size() - tail.size(), tail.size(), tail) == 0) {
    return here.substr(0, here.size() - tail.size());
  }
  return "./";
}

XmlRpc::XmlRpcValue typedScalar(const std::string& text) {
  static const std::regex kInt("[-+]?(0|[1-9][0-9]*)");
  static const std::regex kFloat("[-+]?[0-9]+\\.[0-9]*([eE][-+][0-9]+)?");
  if (text == "true" || text == "false") return XmlRpc::XmlRpcValue(text == "true");
  if (std::regex_match(text, kInt)) return XmlRpc::XmlRpcValue(std::stoi(text));
  if (std::regex_match(text, kFloat)) return XmlRpc::XmlRpcValue(std::stod(text));
  return XmlRpc::XmlRpcValue(text);
}

/// config/matcher.yaml as the parameter server holds it after `rosparam load`. The file uses
/// only nested maps of plain scalars (true/false, integers, decimals with a dot, bare words);
/// anything else fails the test, so that a new construct is noticed here (`evaluate` parses the
/// full YAML 1.1 typing, src/tools/evaluate/evaluate_yaml.h).
XmlRpc::XmlRpcValue readMatcherYaml(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot read " << path;
  static const std::regex kLine("( *)([A-Za-z_][A-Za-z0-9_]*): *([^ #][^#]*?)? *(#.*)?");
  static const std::regex kBlank(" *(#.*)?");
  XmlRpc::XmlRpcValue root;
  root.begin();                                      // an empty struct
  std::vector<std::pair<size_t, std::string>> open;  // (indent, key) of the enclosing maps
  std::string line;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_match(line, kBlank)) continue;
    if (!std::regex_match(line, m, kLine)) {
      ADD_FAILURE() << path << ": unsupported line '" << line << "'";
      continue;
    }
    const size_t indent = m[1].length();
    while (!open.empty() && open.back().first >= indent) open.pop_back();
    XmlRpc::XmlRpcValue* node = &root;
    for (const auto& ns : open) node = &(*node)[ns.second];
    if (!m[3].matched) {
      (*node)[m[2].str()].begin();  // a nested map follows
      open.emplace_back(indent, m[2].str());
    } else {
      (*node)[m[2].str()] = typedScalar(m[3].str());
    }
  }
  return root;
}

ParamSource shippedMatcherParams(bool initial_pose_enabled) {
  const std::string path = repositoryRoot() + "config/matcher.yaml";
  XmlRpc::XmlRpcValue tree = readMatcherYaml(path);
  if (initial_pose_enabled) {
    // As a launch file sets it (test/integration/matcher_ekf_nodelets.test).
    tree["initial_pose"]["enabled"] = true;
    tree["initial_pose"]["x"] = 3.0;
    tree["initial_pose"]["y"] = -20.8;
    tree["initial_pose"]["window_half_xy_m"] = 3.0;
  }
  return ParamSource::fromTree(tree, path + ":");
}

sensor_msgs::PointCloud2::ConstPtr cloudAt(double stamp_s) {
  auto msg = boost::make_shared<sensor_msgs::PointCloud2>();
  msg->header.stamp.fromSec(stamp_s);
  msg->header.frame_id = "base_link";
  return msg;
}

TEST(MatcherSession, ShippedOptionsReachTheNodeletSession) {
  const MatcherOptions options = loadMatcherOptions(shippedMatcherParams(false));
  // The values written in the file.
  EXPECT_EQ(options.session.scan_queue_size, 3);
  EXPECT_DOUBLE_EQ(options.session.time_backwards_tolerance_s, 1.0);
  EXPECT_TRUE(options.session.deskew);
  EXPECT_DOUBLE_EQ(options.session.deskew_twist_max_gap_s, 0.2);
  EXPECT_TRUE(options.session.configured_pose_on_reset);
  EXPECT_EQ(options.registration.filter.max_points, 4000u);  // a nested key was read too

  MatcherSession session = makeMatcherSession(options);
  EXPECT_EQ(session.queueCapacity(), 3u);
  EXPECT_EQ(session.tracker().mode(), PriorMode::kNoPrior);  // initial_pose/enabled: false
  EXPECT_EQ(session.options().time_backwards_tolerance_s, 1.0);

  // `evaluate` builds its pipeline from the same options: the same session, queue included.
  const LocalizerPipelineOptions po = pipelineOptions(options, EkfNodeOptions());
  EXPECT_EQ(po.session.scan_queue_size, 3);
  auto pipeline = LocalizerPipeline::create(po);
  ASSERT_TRUE(pipeline.ok()) << pipeline.error();
}

TEST(MatcherSession, TheShippedQueueDropsTheOldestClouds) {
  MatcherSession session = makeMatcherSession(loadMatcherOptions(shippedMatcherParams(false)));
  // Five clouds at 10 Hz while the worker is busy: the two oldest go.
  std::vector<sensor_msgs::PointCloud2::ConstPtr> clouds;
  size_t dropped = 0;
  for (int i = 0; i < 5; ++i) {
    clouds.push_back(cloudAt(100.0 + 0.1 * i));
    const MatcherSession::Arrival a = session.onScanArrival(100.0 + 0.1 * i);
    EXPECT_FALSE(a.timeWentBackwards());
    dropped += a.dropped + session.enqueue(clouds.back());
  }
  EXPECT_EQ(dropped, 2u);
  EXPECT_EQ(session.waiting(), 3u);
  MatcherSession::Next next = session.takeNext();
  EXPECT_EQ(next.item, clouds[2]);  // the worker takes the oldest still waiting
  EXPECT_EQ(next.dropped_before, 2u);
  next = session.takeNext();
  EXPECT_EQ(next.item, clouds[3]);
  EXPECT_EQ(next.dropped_before, 0u);
  EXPECT_EQ(session.droppedTotal(), 2u);
}

TEST(MatcherSession, TimeGoingBackwardsReArmsTheConfiguredPose) {
  const MatcherOptions options = loadMatcherOptions(shippedMatcherParams(true));
  MatcherSession session = makeMatcherSession(options);
  ScanInput scan;
  scan.stamp_s = 200.0;
  session.onScanArrival(scan.stamp_s);
  MatchStart start = session.beginMatch(scan);
  EXPECT_EQ(start.prior.source, PriorSource::kConfigured);
  EXPECT_DOUBLE_EQ(start.prior.pose.x, 3.0);
  EXPECT_DOUBLE_EQ(start.prior.wide_window.half_x_m, 3.0);  // configuredPoseWindow()

  // The match is accepted: tracking.
  MatchReport accepted;
  accepted.stamp_s = scan.stamp_s;
  accepted.outcome = MatchOutcome::kAccepted;
  accepted.prior = start.prior;
  accepted.pose = start.prior.pose;
  accepted.covariance = Matrix6d::Identity() * 0.01;
  ASSERT_TRUE(session.finishMatch(start.epoch, &accepted));
  EXPECT_EQ(session.tracker().mode(), PriorMode::kTracking);

  // A scan 0.8 s older (within the shipped 1.0 s) is no reset; one 30 s older is.
  session.enqueue(cloudAt(200.1));
  EXPECT_FALSE(session.onScanArrival(199.2).timeWentBackwards());
  const MatcherSession::Arrival back = session.onScanArrival(169.2);
  ASSERT_TRUE(back.timeWentBackwards());
  EXPECT_NEAR(back.backwards_jump_s, 30.0, 1e-9);
  EXPECT_EQ(back.dropped, 1u);  // the waiting cloud of the old timeline
  EXPECT_FALSE(session.hasWaiting());
  scan.stamp_s = 169.2;
  start = session.beginMatch(scan);
  EXPECT_EQ(start.prior.source, PriorSource::kConfigured);
  EXPECT_TRUE(start.prior.wide);
  EXPECT_EQ(start.epoch, 1u);
  // A result of the old timeline finishing now is discarded.
  MatchReport stale = accepted;
  EXPECT_FALSE(session.finishMatch(0, &stale));
  EXPECT_EQ(stale.reason, "discarded: time went backwards during the match");
  EXPECT_EQ(session.tracker().mode(), PriorMode::kRelocalizing);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
