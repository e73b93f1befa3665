// rostest node for the matcher and ekf nodelets (test/integration/matcher_ekf_nodelets.test).
// It plays a recorded drive's part on sim time: /clock, the map (index + chunks of a synthetic
// street world, rasterized in-process), INS odometry + TF odom -> base_link, a level IMU and
// scans from a known, fixed pose. The tests run in order on one running system.
#include "matcher_ekf_nodelets_harness.h"

#include "bad_clouds.h"

#include <algorithm>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/topic.h>
#include <sensor_msgs/Image.h>
#include <std_srvs/Trigger.h>
#include <tf2_eigen/tf2_eigen.h>

namespace gmm_localization {
namespace node {
namespace {

using namespace testing_harness;  // NOLINT: test code

std::unique_ptr<Harness> harness;

void expectNearTruth(const geometry_msgs::Pose& p, double tol_xy, double tol_yaw,
                     const std::string& what) {
  const Pose6 e = fromIsometry(fromMsg(p));
  const Pose6 t = truth();
  EXPECT_LE(std::hypot(e.x - t.x, e.y - t.y), tol_xy) << what << " at " << e.x << ", " << e.y;
  EXPECT_LE(std::abs(angleDiff(e.yaw, t.yaw)), tol_yaw) << what << " yaw " << e.yaw;
}

/// Waits for a status stamped `stamp` (the scan's) satisfying `pred`.
bool waitForStatus(const ros::Time& stamp, const std::function<bool(const MatchStatus&)>& pred,
                   double timeout_s, MatchStatus* found) {
  return Harness::waitFor(
      [&] {
        return harness->locked([&] {
          for (const MatchStatus& s : harness->statuses_) {
            if (s.header.stamp == stamp && pred(s)) {
              *found = s;
              return true;
            }
          }
          return false;
        });
      },
      timeout_s);
}

using StatusPred = std::function<bool(const diagnostic_msgs::DiagnosticStatus&)>;

double wallNow() { return ros::WallTime::now().toSec(); }

/// Whether a status named `name` that satisfies `pred` arrived after wall time `since`.
bool sawDiagnostic(const std::string& name, double since, const StatusPred& pred,
                   diagnostic_msgs::DiagnosticStatus* found = nullptr) {
  return harness->locked([&] {
    for (const auto& [wall, st] : harness->diagnostics_) {
      if (wall >= since && st.name == name && pred(st)) {
        if (found != nullptr) *found = st;
        return true;
      }
    }
    return false;
  });
}

/// The messages of the statuses named `name` since `since`, for failure output.
std::string describeDiagnostics(const std::string& name, double since) {
  return harness->locked([&] {
    std::string all;
    const diagnostic_msgs::DiagnosticStatus* last = nullptr;
    for (const auto& [wall, st] : harness->diagnostics_) {
      if (wall >= since && st.name == name) {
        all += "\n  level " + std::to_string(st.level) + ": " + st.message;
        last = &st;
      }
    }
    if (last == nullptr) return std::string(" none named '") + name + "'";
    all += "\n  the last one's keys:";
    for (const auto& kv : last->values) all += " '" + kv.key + "'";
    return all;
  });
}

/// Whether a WARN (or worse) log line containing every one of `texts` arrived after `since`.
bool sawWarning(const std::vector<std::string>& texts, double since) {
  return harness->locked([&] {
    for (const auto& [wall, log] : harness->logs_) {
      if (wall < since || log.level < rosgraph_msgs::Log::WARN) continue;
      if (std::all_of(texts.begin(), texts.end(),
                      [&](const std::string& t) { return log.msg.find(t) != std::string::npos; })) {
        return true;
      }
    }
    return false;
  });
}

bool warnsWith(const diagnostic_msgs::DiagnosticStatus& s, const std::string& text) {
  return s.level >= diagnostic_msgs::DiagnosticStatus::WARN &&
         s.message.find(text) != std::string::npos;
}

TEST(MatcherEkfNodelets, AcceptedPoseWithinToleranceAndTheEkfFollows) {
  ASSERT_TRUE(harness->publishMap(30.0)) << "the matcher never subscribed to /map_chunks";
  ros::WallDuration(1.0).sleep();  // let the chunks arrive: a partial map is another test
  harness->setStreaming(true);
  ASSERT_TRUE(Harness::waitFor(
      [] { return harness->locked([] { return harness->poses_.size() >= 3; }); }, 60.0))
      << "no accepted pose; statuses: " << harness->locked([] {
           return harness->statuses_.empty() ? std::string("none")
                                             : harness->statuses_.back().reason;
         });
  harness->locked([] {
    for (const auto& p : harness->poses_) {
      EXPECT_EQ(p.header.frame_id, "map");
      expectNearTruth(p.pose.pose, 0.05, 0.005, "matched pose");
    }
    // The first accepted match searched the configured window; later ones track the EKF.
    bool first_accepted = true;
    for (const MatchStatus& s : harness->statuses_) {
      if (!s.accepted) continue;
      if (first_accepted) {
        EXPECT_EQ(s.prior_source, "configured");
        EXPECT_NEAR(s.window_half_x_m, 3.0, 1e-9);
        first_accepted = false;
      }
      EXPECT_GT(s.search_evaluations, 0u);
      EXPECT_GT(s.log_likelihood_per_point, -1.0);  // a clean scan of the mapped world
    }
    return 0;
  });
  // The EKF starts from the first match and publishes odometry (and map -> odom).
  ASSERT_TRUE(Harness::waitFor(
      [] { return harness->locked([] { return harness->odometry_.size() >= 10; }); }, 20.0));
  ASSERT_TRUE(Harness::waitFor(
      [] {
        return harness->locked([] {
          for (const MatchStatus& s : harness->statuses_) {
            if (s.accepted && s.prior_source == "ekf") return true;
          }
          return false;
        });
      },
      20.0))
      << "the matcher never tracked the EKF posterior";
  harness->locked([] {
    const nav_msgs::Odometry& o = harness->odometry_.back();
    EXPECT_EQ(o.header.frame_id, "map");
    EXPECT_EQ(o.child_frame_id, "base_link");
    expectNearTruth(o.pose.pose, 0.1, 0.01, "EKF odometry");
    EXPECT_GT(o.pose.covariance[0], 0.0);
    return 0;
  });
  geometry_msgs::TransformStamped map_base;
  ASSERT_TRUE(Harness::waitFor(
      [&] {
        try {
          map_base = harness->tf_buffer_.lookupTransform("map", "base_link", ros::Time(0));
          return true;
        } catch (const tf2::TransformException&) {
          return false;
        }
      },
      10.0));
  expectNearTruth(node::toMsg(tf2::transformToEigen(map_base)), 0.1, 0.01, "TF map -> base_link");
}

TEST(MatcherEkfNodelets, MalformedEmptyAndNanCloudsGiveStatusReasons) {
  harness->setStreaming(false);
  ros::WallDuration(0.5).sleep();  // let the worker finish what it holds
  const std::vector<CloudCase> cases = unmatchableClouds();
  for (const CloudCase& c : cases) {
    sensor_msgs::PointCloud2 msg = harness->scanAt(harness->simNow());
    c.spoil(msg);
    harness->publishScan(msg);
    MatchStatus s;
    ASSERT_TRUE(waitForStatus(
        msg.header.stamp, [](const MatchStatus&) { return true; }, 10.0, &s))
        << c.what << ": no status";
    EXPECT_FALSE(s.accepted) << c.what;
    EXPECT_NE(s.reason.find(c.reason), std::string::npos) << c.what << ": " << s.reason;
  }
  // A good scan is still accepted afterwards.
  const sensor_msgs::PointCloud2 good = harness->scanAt(harness->simNow());
  harness->publishScan(good);
  MatchStatus s;
  ASSERT_TRUE(waitForStatus(
      good.header.stamp, [](const MatchStatus&) { return true; }, 10.0, &s));
  EXPECT_TRUE(s.accepted) << s.reason;
  harness->setStreaming(true);
}

TEST(MatcherEkfNodelets, DebugOutputsAndDiagnostics) {
  // Published only while subscribed; waitForMessage subscribes.
  const auto image =
      ros::topic::waitForMessage<sensor_msgs::Image>("/search_traversal", ros::Duration(10.0));
  ASSERT_TRUE(image) << "no search_traversal image";
  EXPECT_EQ(image->encoding, "rgb8");
  EXPECT_GT(image->width, 10u);
  EXPECT_EQ(image->data.size(), static_cast<size_t>(image->step) * image->height);
  const auto classified =
      ros::topic::waitForMessage<sensor_msgs::PointCloud2>("/scan_classified", ros::Duration(10.0));
  ASSERT_TRUE(classified) << "no scan_classified cloud";
  EXPECT_EQ(classified->header.frame_id, "map");
  EXPECT_GT(classified->width, 1000u);
  std::vector<std::string> names;
  for (const auto& f : classified->fields) names.push_back(f.name);
  EXPECT_NE(std::find(names.begin(), names.end(), "mahalanobis"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "class"), names.end());
  const auto obstacles =
      ros::topic::waitForMessage<sensor_msgs::PointCloud2>("/obstacles", ros::Duration(10.0));
  ASSERT_TRUE(obstacles) << "no obstacles cloud";
  EXPECT_EQ(obstacles->header.frame_id, "base_link");
  // The scan is of the mapped world: few points are obstacles.
  EXPECT_LT(obstacles->width, classified->width / 5);

  const auto has = [](const char* name) {
    return harness->locked([&] { return harness->diagnostic_names_.count(name) > 0; });
  };
  ASSERT_TRUE(Harness::waitFor(
      [&] { return has("/matcher: scan matching") && has("/ekf: filter") && has("/ekf: inputs"); },
      10.0))
      << "diagnostics seen: " << harness->locked([] {
           std::string all;
           for (const auto& n : harness->diagnostic_names_) all += "'" + n + "' ";
           return all;
         });
  // The standard rate and stamp checks of each input topic (diagnostic_updater's
  // FrequencyStatus and TimeStampStatus), named like diagnostic_updater::TopicDiagnostic's.
  const char* kScanTopic = "/matcher: /velodyne_points topic status";
  auto has_key = [](const diagnostic_msgs::DiagnosticStatus& s, const std::string& key) {
    return std::any_of(s.values.begin(), s.values.end(),
                       [&](const diagnostic_msgs::KeyValue& kv) { return kv.key == key; });
  };
  diagnostic_msgs::DiagnosticStatus scan_topic;
  EXPECT_TRUE(Harness::waitFor(
      [&] {
        return sawDiagnostic(
            kScanTopic, 0.0,
            [&](const diagnostic_msgs::DiagnosticStatus& s) {
              return has_key(s, "Actual frequency (Hz)") && has_key(s, "Latest timestamp delay");
            },
            &scan_topic);
      },
      10.0))
      << "no rate and stamp checks in the scan topic status: "
      << describeDiagnostics(kScanTopic, 0.0);
  EXPECT_TRUE(has("/ekf: /imu topic status") && has("/ekf: /odom topic status"));
  EXPECT_EQ(scan_topic.hardware_id, "/matcher");

  // diagnostic_aggregator with config/analyzers.yaml (started by the .test) groups them.
  auto aggregated = [](const std::string& name) {
    return harness->locked([&] {
      for (const auto& st : harness->aggregated_) {
        if (st.name == name) return true;
      }
      return false;
    });
  };
  EXPECT_TRUE(Harness::waitFor(
      [&] {
        // The task's name under its nodelet's path (analyzers.yaml: remove_prefix).
        return aggregated("/Localization") && aggregated("/Localization/Matcher/scan matching") &&
               aggregated("/Localization/Matcher/velodyne_points topic status") &&
               aggregated("/Localization/EKF/filter") && aggregated("/Localization/EKF/inputs");
      },
      10.0))
      << "/diagnostics_agg: " << harness->locked([] {
           std::string all;
           for (const auto& st : harness->aggregated_) {
             all += "'" + st.name + "' (" + std::to_string(st.level) + ": " + st.message + ") ";
           }
           return all;
         });
}

TEST(MatcherEkfNodelets, ASilentScanTopicIsNamedInTheDiagnosticsAndOnTheConsole) {
  // The scans stop (a driver that died, a bag not played): after 5 s the scan topic's status
  // and a console line name the topic and the launch argument that sets it.
  const char* kScanTopic = "/matcher: /velodyne_points topic status";
  const double since = wallNow();
  harness->setStreaming(false);
  diagnostic_msgs::DiagnosticStatus st;
  ASSERT_TRUE(Harness::waitFor(
      [&] {
        return sawDiagnostic(
            kScanTopic, since,
            [](const diagnostic_msgs::DiagnosticStatus& s) {
              return warnsWith(s, "no messages on /velodyne_points for") &&
                     warnsWith(s, "No events recorded.");
            },
            &st);
      },
      12.0))
      << describeDiagnostics(kScanTopic, since);
  EXPECT_NE(st.message.find("points_topic"), std::string::npos) << st.message;
  // Not before 5 s of silence (the last scan went out at most 0.2 s before `since`).
  const double first = harness->locked([&] {
    for (const auto& [wall, d] : harness->diagnostics_) {
      if (wall >= since && d.name == kScanTopic && warnsWith(d, "no messages on")) return wall;
    }
    return -1.0;
  });
  EXPECT_GE(first - since, 4.5) << "the silence was reported too early";
  EXPECT_TRUE(sawWarning({"no messages on /velodyne_points for", "points_topic"}, since))
      << "no console line for the silent scan topic";

  // Scans again: matched again.
  harness->setStreaming(true);
  const double resumed = harness->simNow();
  EXPECT_TRUE(Harness::waitFor(
      [&] {
        return harness->locked([&] {
          for (const MatchStatus& s : harness->statuses_) {
            if (s.header.stamp.toSec() > resumed && s.accepted) return true;
          }
          return false;
        });
      },
      20.0))
      << "no accepted match after the scans came back";
}

TEST(MatcherEkfNodelets, RelocalizeWidensTheWindowAndInitialPoseIsSearched) {
  std_srvs::Trigger trigger;
  ASSERT_TRUE(ros::service::waitForService("/relocalize", 5000));
  ASSERT_TRUE(ros::service::call("/relocalize", trigger));
  EXPECT_TRUE(trigger.response.success) << trigger.response.message;
  const double after = harness->simNow();
  // The EKF's inflated covariance gives the matcher its widest window; the match is accepted
  // and fused, and the windows shrink again.
  auto accepted_with = [&](double since, const std::function<bool(const MatchStatus&)>& pred) {
    return Harness::waitFor(
        [&] {
          return harness->locked([&] {
            for (const MatchStatus& s : harness->statuses_) {
              if (s.header.stamp.toSec() > since && s.accepted && pred(s)) return true;
            }
            return false;
          });
        },
        20.0);
  };
  EXPECT_TRUE(accepted_with(after, [](const MatchStatus& s) {
    return s.prior_source == "ekf" && s.window_half_x_m > 12.4;
  })) << "no accepted match in the widest window after relocalize";
  EXPECT_TRUE(accepted_with(after, [](const MatchStatus& s) { return s.window_half_x_m < 3.0; }))
      << "the window did not shrink again";

  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>("/initialpose", 1);
  // matcher and ekf share the manager process: one subscriber link.
  ASSERT_TRUE(Harness::waitFor([&] { return pub.getNumSubscribers() >= 1; }, 5.0));
  ros::WallDuration(0.2).sleep();
  auto publishClick = [&](double dx, double dy) {
    geometry_msgs::PoseWithCovarianceStamped click;
    click.header.frame_id = "map";
    click.header.stamp.fromSec(harness->simNow());
    Pose6 p = truth();
    p.x += dx;
    p.y += dy;
    p.z = 0.0;
    click.pose.pose = toMsg(p);
    click.pose.covariance[0] = click.pose.covariance[7] = 0.25;
    click.pose.covariance[35] = 0.0685;
    pub.publish(click);
    return click.header.stamp.toSec();
  };
  // A click 500 m away, off the map: statuses say so, nothing is published from there.
  const double off_map_wall = wallNow();
  const double off_map = publishClick(500.0, 0.0);
  MatchStatus off;
  ASSERT_TRUE(Harness::waitFor(
      [&] {
        return harness->locked([&] {
          for (const MatchStatus& s : harness->statuses_) {
            if (s.header.stamp.toSec() > off_map && s.prior_source == "initialpose") {
              off = s;
              return true;
            }
          }
          return false;
        });
      },
      10.0));
  EXPECT_FALSE(off.accepted);
  EXPECT_NE(off.reason.find("off the map"), std::string::npos) << off.reason;
  // Rejected scan after scan from there (the global search of the lost mode included), none
  // accepted: the matcher tells the user to give a pose near the vehicle on /initialpose.
  const char* kMatching = "/matcher: scan matching";
  EXPECT_TRUE(Harness::waitFor(
      [&] {
        return sawDiagnostic(kMatching, off_map_wall,
                             [](const diagnostic_msgs::DiagnosticStatus& s) {
                               return warnsWith(s, "scans around the initialpose pose") &&
                                      warnsWith(s, "/initialpose");
                             });
      },
      20.0))
      << describeDiagnostics(kMatching, off_map_wall);
  EXPECT_TRUE(sawWarning({"no match accepted in", "around the initialpose pose (x 502.",
                          "a pose within a few metres of the vehicle on /initialpose"},
                         off_map_wall))
      << "no console line for the initial pose that is never matched";

  // rviz "2D Pose Estimate", 2 m off (z = 0: completed from the posterior).
  const double click_stamp = publishClick(-1.5, 1.3);
  // The first scan searched around the click may be stamped before it (a scan waits up to a
  // revolution and its latency): look from half a second earlier. The statuses there around
  // the off-map pose are all rejected, so nothing older can pass for this match.
  EXPECT_TRUE(accepted_with(click_stamp - 0.5,
                            [](const MatchStatus& s) {
                              return s.prior_source == "initialpose" && s.window_half_x_m > 12.4;
                            }))
      << "no accepted match around the initial pose; statuses: " << harness->locked([&] {
           std::string all;
           for (const MatchStatus& st : harness->statuses_) {
             if (st.header.stamp.toSec() < after) continue;
             all += std::to_string(st.header.stamp.toSec()) + " " + st.prior_source + " " +
                    std::to_string(st.window_half_x_m) + " " + (st.accepted ? "ok" : st.reason) +
                    "\n";
           }
           return all;
         });
  ros::WallDuration(1.0).sleep();
  harness->locked([] {
    expectNearTruth(harness->poses_.back().pose.pose, 0.05, 0.005, "after initialpose");
    expectNearTruth(harness->odometry_.back().pose.pose, 0.1, 0.01, "EKF after initialpose");
    return 0;
  });
}

TEST(MatcherEkfNodelets, ClockJumpingBackResetsAndBothRecover) {
  // The clock jumps back to 40 s before the start: every stamp of the new timeline during the
  // next 15 s is below kStartS - 25, every stamp before the loop at or above kStartS.
  const double new_timeline = kStartS - 25.0;
  const size_t statuses_before = harness->locked([] { return harness->statuses_.size(); });
  harness->loop(harness->simNow() - kStartS + 40.0);  // /clock and every stamp
  // The matcher reports the reset.
  ASSERT_TRUE(Harness::waitFor(
      [&] {
        return harness->locked([&] {
          for (size_t i = statuses_before; i < harness->statuses_.size(); ++i) {
            if (harness->statuses_[i].reason.find("time went backwards") != std::string::npos) {
              return true;
            }
          }
          return false;
        });
      },
      10.0))
      << "no 'time went backwards' status";
  // Both recover on the new timeline: accepted matches and EKF odometry stamped on it.
  ASSERT_TRUE(Harness::waitFor(
      [&] {
        return harness->locked([&] {
          int matches = 0, estimates = 0;
          for (const auto& p : harness->poses_) matches += p.header.stamp.toSec() < new_timeline;
          for (const auto& o : harness->odometry_) {
            estimates += o.header.stamp.toSec() < new_timeline;
          }
          return matches >= 3 && estimates >= 10;
        });
      },
      30.0))
      << "no recovery after the clock went back";
  harness->locked([&] {
    for (const auto& p : harness->poses_) {
      if (p.header.stamp.toSec() < new_timeline) expectNearTruth(p.pose.pose, 0.05, 0.005, "after");
    }
    expectNearTruth(harness->odometry_.back().pose.pose, 0.1, 0.01, "EKF after the loop");
    return 0;
  });
}

TEST(MatcherEkfNodelets, NothingNonFiniteWasPublished) {
  harness->locked([] {
    EXPECT_FALSE(harness->non_finite_) << harness->non_finite_what_;
    EXPECT_FALSE(harness->statuses_.empty());
    return 0;
  });
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "matcher_ekf_nodelets_test");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  gmm_localization::node::harness =
      std::make_unique<gmm_localization::node::testing_harness::Harness>();
  const int result = RUN_ALL_TESTS();
  gmm_localization::node::harness.reset();
  spinner.stop();
  return result;
}
