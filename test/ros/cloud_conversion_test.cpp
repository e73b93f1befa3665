// sensor_msgs/PointCloud2 <-> CloudData (cloud_conversion.h): round trips, the field types a
// LIDAR driver may use, organised clouds with row padding, and malformed clouds rejected with a
// reason (missing fields, sizes that disagree, wrong types, big-endian).
#include "gmm_localization/ros/cloud_conversion.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>

namespace gmm_localization {
namespace node {
namespace {

using sensor_msgs::PointCloud2;
using sensor_msgs::PointField;

CloudData sample(size_t n) {
  CloudData c;
  for (size_t i = 0; i < n; ++i) {
    c.points.emplace_back(0.5f * i, -1.0f * i, 0.25f * i - 3.f);
    c.time_s.push_back(1e-4f * i);
    c.intensity.push_back(static_cast<float>(i % 256));
    c.ring.push_back(static_cast<uint16_t>(i % 32));
    c.label.push_back(static_cast<uint8_t>(i % 3));
  }
  return c;
}

const PointField* field(const PointCloud2& m, const std::string& name) {
  for (const auto& f : m.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

/// A cloud with the given fields (name, datatype) packed in order, rows padded by row_pad bytes.
PointCloud2 makeCloud(const std::vector<std::pair<std::string, uint8_t>>& fields, uint32_t width,
                      uint32_t height, uint32_t row_pad = 0) {
  PointCloud2 m;
  uint32_t offset = 0;
  for (const auto& [name, type] : fields) {
    PointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = type;
    f.count = 1;
    m.fields.push_back(f);
    offset += type == PointField::FLOAT64                                 ? 8
              : (type == PointField::UINT16 || type == PointField::INT16) ? 2
              : (type == PointField::UINT8 || type == PointField::INT8)   ? 1
                                                                          : 4;
  }
  m.width = width;
  m.height = height;
  m.point_step = offset;
  m.row_step = offset * width + row_pad;
  m.data.assign(static_cast<size_t>(m.row_step) * height, 0);
  return m;
}

template <typename T>
void put(PointCloud2& m, size_t row, size_t col, const std::string& name, T v) {
  const PointField* f = field(m, name);
  ASSERT_NE(f, nullptr);
  std::memcpy(m.data.data() + row * m.row_step + col * m.point_step + f->offset, &v, sizeof(T));
}

TEST(CloudConversion, RoundTripKeepsEveryField) {
  const CloudData in = sample(100);
  PointCloud2 msg;
  toMsg(in, msg);
  EXPECT_EQ(msg.width, 100u);
  EXPECT_EQ(msg.height, 1u);
  EXPECT_FALSE(msg.is_bigendian);
  EXPECT_EQ(msg.data.size(), static_cast<size_t>(msg.row_step));
  for (const char* name : {"x", "y", "z", "intensity", "time", "ring", "label"}) {
    EXPECT_NE(field(msg, name), nullptr) << name;
  }
  auto out = fromMsg(msg);
  ASSERT_TRUE(out.ok()) << out.error();
  EXPECT_EQ(out->points, in.points);
  EXPECT_EQ(out->time_s, in.time_s);
  EXPECT_EQ(out->intensity, in.intensity);
  EXPECT_EQ(out->ring, in.ring);
  EXPECT_EQ(out->label, in.label);
}

TEST(CloudConversion, OptionalFieldsAndExtraFloat) {
  CloudData in = sample(10);
  in.ring.clear();
  in.label.resize(3);  // size disagrees with the points: left out, not written half
  std::vector<float> likelihood(10, -1.5f);
  PointCloud2 msg;
  toMsg(in, msg, "likelihood", likelihood);
  EXPECT_EQ(field(msg, "ring"), nullptr);
  EXPECT_EQ(field(msg, "label"), nullptr);
  ASSERT_NE(field(msg, "likelihood"), nullptr);
  auto out = fromMsg(msg);
  ASSERT_TRUE(out.ok());
  EXPECT_TRUE(out->ring.empty());
  EXPECT_TRUE(out->label.empty());
  EXPECT_EQ(out->time_s, in.time_s);
  float v;
  std::memcpy(&v, msg.data.data() + 3 * msg.point_step + field(msg, "likelihood")->offset, 4);
  EXPECT_EQ(v, -1.5f);
}

TEST(CloudConversion, NanPointsAreKept) {
  CloudData in = sample(3);
  in.points[1].x() = std::numeric_limits<float>::quiet_NaN();
  PointCloud2 msg;
  toMsg(in, msg);
  auto out = fromMsg(msg);
  ASSERT_TRUE(out.ok());
  ASSERT_EQ(out->points.size(), 3u);
  EXPECT_TRUE(std::isnan(out->points[1].x()));
}

TEST(CloudConversion, EmptyCloud) {
  PointCloud2 msg;
  toMsg(CloudData(), msg);
  auto out = fromMsg(msg);
  ASSERT_TRUE(out.ok()) << out.error();
  EXPECT_TRUE(out->points.empty());
}

// Fuzz reproducer test/fuzz/regressions/pointcloud2/timeout_height_2e32_width_0: width 0,
// height 2^32 - 1, row_step 0, no data passes every size check (0 points), and the row loop
// then ran 2^32 times (67 s in the sanitizer build). Now the empty cloud, at once, as for the
// other empty clouds; the field checks still apply.
TEST(CloudConversion, ZeroWidthCloudOfMaximalHeightIsEmptyAtOnce) {
  PointCloud2 m = makeCloud({{"x", PointField::FLOAT32},
                             {"y", PointField::FLOAT32},
                             {"z", PointField::FLOAT32},
                             {"intensity", PointField::FLOAT32},
                             {"t", PointField::UINT32},
                             {"ring", PointField::UINT16},
                             {"label", PointField::UINT8}},
                            0, 1);
  m.height = std::numeric_limits<uint32_t>::max();
  m.row_step = 0;
  m.data.clear();
  const auto start = std::chrono::steady_clock::now();
  auto out = fromMsg(m);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(out.ok()) << out.error();
  EXPECT_TRUE(out->points.empty());
  EXPECT_TRUE(out->time_s.empty());
  EXPECT_TRUE(out->intensity.empty());
  EXPECT_TRUE(out->ring.empty());
  EXPECT_TRUE(out->label.empty());
  EXPECT_LT(seconds, 0.1) << "the empty rows were visited";
  // An empty cloud still needs x, y and z.
  m.fields.clear();
  EXPECT_NE(fromMsg(m).error().find("x, y or z"), std::string::npos);
}

TEST(CloudConversion, Float64XyzOusterTimeAndOrganisedRows) {
  // 3 x 2 organised cloud, float64 x/y/z, uint32 "t" in nanoseconds, 5 bytes of row padding.
  PointCloud2 m = makeCloud({{"x", PointField::FLOAT64},
                             {"y", PointField::FLOAT64},
                             {"z", PointField::FLOAT64},
                             {"t", PointField::UINT32},
                             {"ring", PointField::UINT16}},
                            3, 2, 5);
  for (size_t r = 0; r < 2; ++r) {
    for (size_t c = 0; c < 3; ++c) {
      put<double>(m, r, c, "x", 1.0 + c);
      put<double>(m, r, c, "y", 10.0 * r);
      put<double>(m, r, c, "z", -2.0);
      put<uint32_t>(m, r, c, "t", static_cast<uint32_t>(1000000 * (r * 3 + c)));
      put<uint16_t>(m, r, c, "ring", static_cast<uint16_t>(r));
    }
  }
  auto out = fromMsg(m);
  ASSERT_TRUE(out.ok()) << out.error();
  ASSERT_EQ(out->points.size(), 6u);
  EXPECT_EQ(out->points[4], Eigen::Vector3f(2.f, 10.f, -2.f));
  EXPECT_NEAR(out->time_s[5], 0.005, 1e-9);
  EXPECT_EQ(out->ring[3], 1);
  EXPECT_TRUE(out->intensity.empty());
}

/// fromMsg of a valid float32 x/y/z/intensity cloud after `mutate` fails mentioning `what`.
template <typename F>
void expectRejected(F mutate, const std::string& what) {
  PointCloud2 msg;
  toMsg(sample(8), msg);
  mutate(msg);
  auto r = fromMsg(msg);
  ASSERT_FALSE(r.ok()) << "accepted a cloud that should fail with '" << what << "'";
  EXPECT_NE(r.error().find(what), std::string::npos) << r.error();
}

TEST(CloudConversion, MalformedCloudsAreRejected) {
  auto remove = [](const std::string& name) {
    return [name](PointCloud2& m) {
      for (auto it = m.fields.begin(); it != m.fields.end(); ++it) {
        if (it->name == name) {
          m.fields.erase(it);
          return;
        }
      }
    };
  };
  expectRejected(remove("x"), "x, y or z");
  expectRejected(remove("z"), "x, y or z");
  expectRejected([](PointCloud2& m) { m.is_bigendian = true; }, "big-endian");
  expectRejected([](PointCloud2& m) { m.data.pop_back(); }, "data size");
  expectRejected([](PointCloud2& m) { m.width += 1; }, "exceeds row_step");
  expectRejected([](PointCloud2& m) { m.height = 2; }, "data size");
  expectRejected(
      [](PointCloud2& m) {
        m.point_step = 0;
        m.row_step = 0;
        m.data.clear();
      },
      "point_step is 0");
  expectRejected(
      [](PointCloud2& m) {
        m.fields[0].datatype = PointField::INT32;  // x as an integer
      },
      "float32 or float64");
  expectRejected([](PointCloud2& m) { m.fields[1].datatype = 99; }, "must be float32");
  expectRejected([](PointCloud2& m) { m.fields[3].datatype = 42; }, "unknown datatype");
  expectRejected([](PointCloud2& m) { m.fields[3].count = 0; }, "count 0");
  expectRejected([](PointCloud2& m) { m.fields[2].offset = m.point_step - 2; }, "does not fit");
  expectRejected(
      [](PointCloud2& m) {
        // A field that would read past the point: offset beyond point_step.
        m.fields.back().offset = m.point_step;
      },
      "does not fit");
}

TEST(CloudConversion, OutOfRangeRingAndLabelValuesRejectTheCloud) {
  const double kNan = std::numeric_limits<double>::quiet_NaN();
  const double kInf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* field;
    double value;
  };
  for (const Case& c :
       {Case{"ring", 70000.0}, Case{"ring", -1.0}, Case{"ring", kNan}, Case{"ring", 1e30},
        Case{"label", 256.0}, Case{"label", -kInf}, Case{"label", kNan}, Case{"label", 3e9}}) {
    for (uint8_t type : {PointField::FLOAT32, PointField::FLOAT64}) {
      PointCloud2 m = makeCloud({{"x", PointField::FLOAT32},
                                 {"y", PointField::FLOAT32},
                                 {"z", PointField::FLOAT32},
                                 {"ring", type},
                                 {"label", type}},
                                4, 1);
      if (type == PointField::FLOAT32) {
        put<float>(m, 0, 2, c.field, static_cast<float>(c.value));
      } else {
        put<double>(m, 0, 2, c.field, c.value);
      }
      auto r = fromMsg(m);
      ASSERT_FALSE(r.ok()) << c.field << " " << c.value;
      EXPECT_NE(r.error().find(std::string("field '") + c.field + "' of point 2"),
                std::string::npos)
          << r.error();
    }
  }
  // In-range float values, the extremes included, are accepted (fractions truncated); an int32
  // ring beyond uint16 is rejected too.
  PointCloud2 m = makeCloud({{"x", PointField::FLOAT32},
                             {"y", PointField::FLOAT32},
                             {"z", PointField::FLOAT32},
                             {"ring", PointField::FLOAT32},
                             {"label", PointField::FLOAT64}},
                            3, 1);
  put<float>(m, 0, 0, "ring", 65535.f);
  put<double>(m, 0, 0, "label", 255.0);
  put<float>(m, 0, 1, "ring", 7.9f);
  put<double>(m, 0, 1, "label", 2.0);
  auto ok = fromMsg(m);
  ASSERT_TRUE(ok.ok()) << ok.error();
  EXPECT_EQ(ok->ring, (std::vector<uint16_t>{65535, 7, 0}));
  EXPECT_EQ(ok->label, (std::vector<uint8_t>{255, 2, 0}));
  m = makeCloud({{"x", PointField::FLOAT32},
                 {"y", PointField::FLOAT32},
                 {"z", PointField::FLOAT32},
                 {"ring", PointField::INT32}},
                2, 1);
  put<int32_t>(m, 0, 1, "ring", 65536);
  EXPECT_NE(fromMsg(m).error().find("field 'ring' of point 1 is 65536"), std::string::npos);
}

TEST(CloudConversion, Float64CoordinatesBeyondFloatRangeBecomeInfinite) {
  PointCloud2 m = makeCloud({{"x", PointField::FLOAT64},
                             {"y", PointField::FLOAT64},
                             {"z", PointField::FLOAT64},
                             {"intensity", PointField::FLOAT64}},
                            2, 1);
  put<double>(m, 0, 0, "x", 1e300);
  put<double>(m, 0, 0, "y", -1e300);
  put<double>(m, 0, 0, "intensity", 1e60);
  put<double>(m, 0, 1, "x", 1.5);
  auto r = fromMsg(m);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_TRUE(std::isinf(r->points[0].x()) && r->points[0].x() > 0.f);
  EXPECT_TRUE(std::isinf(r->points[0].y()) && r->points[0].y() < 0.f);
  EXPECT_TRUE(std::isinf(r->intensity[0]));
  EXPECT_EQ(r->points[1].x(), 1.5f);
}

// --- Per-point times of other drivers (interpretPointTimes): relative or absolute, s or ns,
// told apart by magnitude against the stamp; times that make no sense are refused (not
// deskewed, with a reason), never used.

const ros::Time kStamp(1700000000, 250000000);  // a 2023 stamp [s, ns]

/// A cloud of n points along x with the given fields after x, y, z; time(i) written into
/// `time_name` as `TimeT`.
template <typename TimeT, typename F>
PointCloud2 timedCloud(const std::vector<std::pair<std::string, uint8_t>>& extra,
                       const std::string& time_name, size_t n, F time) {
  std::vector<std::pair<std::string, uint8_t>> fields = {
      {"x", PointField::FLOAT32}, {"y", PointField::FLOAT32}, {"z", PointField::FLOAT32}};
  fields.insert(fields.end(), extra.begin(), extra.end());
  PointCloud2 m = makeCloud(fields, static_cast<uint32_t>(n), 1);
  m.header.stamp = kStamp;
  for (size_t i = 0; i < n; ++i) {
    put<float>(m, 0, i, "x", 1.0f + i);
    put<TimeT>(m, 0, i, time_name, static_cast<TimeT>(time(i)));
  }
  return m;
}

TEST(CloudConversionTimes, HesaiAbsoluteFloat64SecondsAfterTheStamp) {
  // HesaiLidar_ROS_2.0 PointXYZIT: x y z intensity, float64 timestamp [s since the epoch],
  // uint16 ring; the stamp is the first point's time.
  const double stamp = kStamp.toSec();
  PointCloud2 m = timedCloud<double>({{"intensity", PointField::FLOAT32},
                                      {"timestamp", PointField::FLOAT64},
                                      {"ring", PointField::UINT16}},
                                     "timestamp", 101, [&](size_t i) { return stamp + 1e-3 * i; });
  auto c = fromMsg(m);
  ASSERT_TRUE(c.ok()) << c.error();
  ASSERT_EQ(c->time_kind, PointTimeKind::kAbsoluteSeconds);
  EXPECT_EQ(c->time_field, "timestamp");
  EXPECT_TRUE(c->time_problem.empty()) << c->time_problem;
  EXPECT_EQ(describePointTimes(*c), "'timestamp' float64 absolute seconds");
  ASSERT_EQ(c->time_s.size(), 101u);
  for (size_t i = 0; i < 101; ++i) EXPECT_NEAR(c->time_s[i], 1e-3 * i, 1e-6) << i;
}

TEST(CloudConversionTimes, RoboSenseAbsoluteSecondsBeforeALastPointStamp) {
  // rslidar_sdk PointXYZIRT: x y z, uint8 intensity, uint16 ring, float64 timestamp; by default
  // the stamp is the last point's time, so every relative time is <= 0.
  const double stamp = kStamp.toSec();
  PointCloud2 m =
      timedCloud<double>({{"intensity", PointField::UINT8},
                          {"ring", PointField::UINT16},
                          {"timestamp", PointField::FLOAT64}},
                         "timestamp", 50, [&](size_t i) { return stamp - 0.1 + 0.1 * i / 49.0; });
  auto c = fromMsg(m);
  ASSERT_TRUE(c.ok()) << c.error();
  ASSERT_EQ(c->time_kind, PointTimeKind::kAbsoluteSeconds);
  EXPECT_NEAR(c->time_s.front(), -0.1, 1e-6);
  EXPECT_NEAR(c->time_s.back(), 0.0, 1e-6);
}

TEST(CloudConversionTimes, LivoxAbsoluteFloat64Nanoseconds) {
  // livox_ros_driver2 PointCloud2 (xfer_format 0): x y z intensity, uint8 tag and line, float64
  // timestamp [ns since the epoch] at offset 18; the stamp is the packet's base time.
  const double stamp_ns = 1e9 * kStamp.sec + kStamp.nsec;
  PointCloud2 m = timedCloud<double>(
      {{"intensity", PointField::FLOAT32},
       {"tag", PointField::UINT8},
       {"line", PointField::UINT8},
       {"timestamp", PointField::FLOAT64}},
      "timestamp", 40, [&](size_t i) { return stamp_ns + 2500000.0 * i; });  // 2.5 ms apart
  ASSERT_EQ(field(m, "timestamp")->offset, 18u);
  auto c = fromMsg(m);
  ASSERT_TRUE(c.ok()) << c.error();
  ASSERT_EQ(c->time_kind, PointTimeKind::kAbsoluteNanoseconds);
  for (size_t i = 0; i < 40; ++i) EXPECT_NEAR(c->time_s[i], 2.5e-3 * i, 1e-6) << i;
  // The same field holding nanoseconds after the stamp: refused (float nanoseconds after the
  // stamp are not read, any garbage would pass as them).
  m = timedCloud<double>({{"timestamp", PointField::FLOAT64}}, "timestamp", 40,
                         [&](size_t i) { return 2500000.0 * i; });
  c = fromMsg(m);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->time_kind, PointTimeKind::kRefused);
}

TEST(CloudConversionTimes, AbsoluteFloat64TimeIsNoLongerTakenAsRelative) {
  // Before: deskewed by 1.7e9 s. Now: absolute seconds, converted to seconds after the stamp.
  const double stamp = kStamp.toSec();
  PointCloud2 m = timedCloud<double>({{"time", PointField::FLOAT64}}, "time", 10,
                                     [&](size_t i) { return stamp + 0.01 * i - 0.05; });
  auto c = fromMsg(m);
  ASSERT_TRUE(c.ok());
  ASSERT_EQ(c->time_kind, PointTimeKind::kAbsoluteSeconds);
  EXPECT_NEAR(c->time_s[0], -0.05, 1e-6);
  EXPECT_NEAR(c->time_s[9], 0.04, 1e-6);
}

TEST(CloudConversionTimes, VelodyneAndOusterTimesAtARealStampAreUnchanged) {
  // velodyne_pointcloud: float32 `time` after the stamp, negative when the stamp is the end.
  PointCloud2 m = timedCloud<float>({{"time", PointField::FLOAT32}}, "time", 11,
                                    [](size_t i) { return -0.1f + 0.01f * i; });
  auto c = fromMsg(m);
  ASSERT_TRUE(c.ok());
  ASSERT_EQ(c->time_kind, PointTimeKind::kRelativeSeconds);
  EXPECT_EQ(describePointTimes(*c), "'time' float32 relative seconds");
  for (size_t i = 0; i < 11; ++i) EXPECT_EQ(c->time_s[i], -0.1f + 0.01f * i);
  // Ouster: uint32 `t` [ns after the stamp].
  m = timedCloud<uint32_t>({{"t", PointField::UINT32}}, "t", 11,
                           [](size_t i) { return 9000000u * i; });
  c = fromMsg(m);
  ASSERT_TRUE(c.ok());
  ASSERT_EQ(c->time_kind, PointTimeKind::kRelativeNanoseconds);
  EXPECT_NEAR(c->time_s[10], 0.09, 1e-8);
  // No time field: nothing to say.
  m = timedCloud<float>({{"intensity", PointField::FLOAT32}}, "intensity", 3,
                        [](size_t) { return 1.f; });
  c = fromMsg(m);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->time_kind, PointTimeKind::kNone);
  EXPECT_TRUE(c->time_s.empty());
  EXPECT_TRUE(c->time_problem.empty());
  EXPECT_EQ(describePointTimes(*c), "");
}

/// fromMsg accepts the cloud but refuses its times, with a problem containing every `what`.
void expectTimesRefused(const PointCloud2& m, const std::vector<std::string>& what) {
  auto c = fromMsg(m);
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(c->points.size(), size_t{m.width} * m.height);
  EXPECT_EQ(c->time_kind, PointTimeKind::kRefused);
  EXPECT_TRUE(c->time_s.empty());
  for (const std::string& w : what) {
    EXPECT_NE(c->time_problem.find(w), std::string::npos) << "'" << w << "' in " << c->time_problem;
  }
  EXPECT_EQ(describePointTimes(*c), "");
}

TEST(CloudConversionTimes, TimesThatMakeNoSenseAreRefusedWithAReason) {
  // A LIDAR clock that is not the stamp's (seconds since the sensor booted).
  expectTimesRefused(timedCloud<double>({{"timestamp", PointField::FLOAT64}}, "timestamp", 10,
                                        [](size_t i) { return 1234.5 + 0.01 * i; }),
                     {"per-point 'timestamp' (float64)", "makes no sense", "1234.5", "away"});
  // Absolute, but 5 s before the stamp (a driver stamping with the receive time).
  expectTimesRefused(timedCloud<double>({{"timestamp", PointField::FLOAT64}}, "timestamp", 10,
                                        [](size_t i) { return kStamp.toSec() - 5.0 + 0.01 * i; }),
                     {"read as absolute seconds", "more than 1 s away"});
  // Within a second of the stamp but spanning 1.6 s.
  expectTimesRefused(timedCloud<float>({{"time", PointField::FLOAT32}}, "time", 17,
                                       [](size_t i) { return -0.8f + 0.1f * i; }),
                     {"'time' (float32)", "a span over 1 s"});
  // Ouster-like nanoseconds spanning 4 s.
  expectTimesRefused(timedCloud<uint32_t>({{"t", PointField::UINT32}}, "t", 5,
                                          [](size_t i) { return 1000000000u * i; }),
                     {"'t' (uint32)"});
  // Absolute seconds in float32: steps of 128 s cannot time a revolution.
  expectTimesRefused(timedCloud<float>({{"time", PointField::FLOAT32}}, "time", 5,
                                       [](size_t) { return static_cast<float>(1.7e9); }),
                     {"too coarse"});
  // A point with finite coordinates and a NaN time.
  PointCloud2 m = timedCloud<double>({{"timestamp", PointField::FLOAT64}}, "timestamp", 6,
                                     [](size_t) { return kStamp.toSec(); });
  put<double>(m, 0, 3, "timestamp", std::numeric_limits<double>::quiet_NaN());
  expectTimesRefused(m, {"not finite for 1 of the 6 points"});
  // 1- and 2-byte integer times: the unit is unknown.
  expectTimesRefused(
      timedCloud<uint16_t>({{"time", PointField::UINT16}}, "time", 3, [](size_t i) { return i; }),
      {"'time' (uint16)", "unit"});
}

TEST(CloudConversionTimes, NonFinitePointsTimesAreIgnored) {
  // Organised clouds mark missing returns with NaN coordinates; their times do not count.
  PointCloud2 m = timedCloud<double>({{"timestamp", PointField::FLOAT64}}, "timestamp", 4,
                                     [](size_t i) { return kStamp.toSec() + 0.01 * i; });
  put<float>(m, 0, 1, "x", std::numeric_limits<float>::quiet_NaN());
  put<double>(m, 0, 1, "timestamp", std::numeric_limits<double>::quiet_NaN());
  put<float>(m, 0, 2, "y", std::numeric_limits<float>::infinity());
  put<double>(m, 0, 2, "timestamp", 0.0);  // garbage, but the point is dropped anyway
  auto c = fromMsg(m);
  ASSERT_TRUE(c.ok());
  ASSERT_EQ(c->time_kind, PointTimeKind::kAbsoluteSeconds);
  EXPECT_NEAR(c->time_s[3], 0.03, 1e-6);
  EXPECT_TRUE(std::isnan(c->time_s[1]));
  // No usable point at all: converted as the first reading, nothing to check.
  const PointTimes t =
      interpretPointTimes("time", PointField::FLOAT32, {5.0, 7.0}, {false, false}, kStamp);
  ASSERT_EQ(t.kind, PointTimeKind::kRelativeSeconds);
  EXPECT_EQ(t.time_s, (std::vector<float>{5.f, 7.f}));
}

TEST(CloudConversionTimes, TheFirstFieldThatMakesSenseIsUsed) {
  // `time` garbage, `timestamp` absolute: the timestamp is used, nothing is refused.
  PointCloud2 m =
      timedCloud<float>({{"time", PointField::FLOAT32}, {"timestamp", PointField::FLOAT64}}, "time",
                        5, [](size_t) { return 99.f; });
  for (size_t i = 0; i < 5; ++i) put<double>(m, 0, i, "timestamp", kStamp.toSec() + 0.02 * i);
  auto c = fromMsg(m);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->time_field, "timestamp");
  ASSERT_EQ(c->time_kind, PointTimeKind::kAbsoluteSeconds);
  EXPECT_TRUE(c->time_problem.empty());
  EXPECT_NEAR(c->time_s[4], 0.08, 1e-6);
  // Both make sense: `time` comes first.
  for (size_t i = 0; i < 5; ++i) put<float>(m, 0, i, "time", 0.01f * i);
  c = fromMsg(m);
  ASSERT_EQ(c->time_field, "time");
  ASSERT_EQ(c->time_s.size(), 5u);
  EXPECT_NEAR(c->time_s[4], 0.04, 1e-7);
  // A named field only: the other is not looked at.
  c = fromMsg(m, "timestamp");
  EXPECT_EQ(c->time_field, "timestamp");
  c = fromMsg(m, "no_such_field");
  EXPECT_EQ(c->time_kind, PointTimeKind::kNone);
  EXPECT_TRUE(c->time_s.empty());
  // Neither makes sense: both reasons, the first field named.
  for (size_t i = 0; i < 5; ++i) put<double>(m, 0, i, "timestamp", 3.0);
  for (size_t i = 0; i < 5; ++i) put<float>(m, 0, i, "time", 99.f);
  c = fromMsg(m);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->time_kind, PointTimeKind::kRefused);
  ASSERT_EQ(c->time_field, "time");
  EXPECT_NE(c->time_problem.find("'time'"), std::string::npos);
  EXPECT_NE(c->time_problem.find("; per-point 'timestamp'"), std::string::npos) << c->time_problem;
}

TEST(CloudConversionTimes, NearAZeroStampTheNearerReadingWins) {
  // Sim time: a stamp of 0.5 s. Absolute seconds around it are nearer as absolute...
  const ros::Time stamp(0, 500000000);
  PointTimes t = interpretPointTimes("time", PointField::FLOAT64, {0.45, 0.5, 0.55}, {}, stamp);
  ASSERT_EQ(t.kind, PointTimeKind::kAbsoluteSeconds);
  EXPECT_NEAR(t.time_s[0], -0.05, 1e-7);
  // ... relative times (a revolution ending at the stamp) stay relative ...
  t = interpretPointTimes("time", PointField::FLOAT32, {-0.1, -0.05, 0.0}, {}, stamp);
  ASSERT_EQ(t.kind, PointTimeKind::kRelativeSeconds);
  EXPECT_NEAR(t.time_s[0], -0.1, 1e-7);
  // ... and a tie is relative (the stamp 0 of a cloud written by toMsg).
  t = interpretPointTimes("time", PointField::FLOAT32, {0.0, 0.01}, {}, ros::Time());
  ASSERT_EQ(t.kind, PointTimeKind::kRelativeSeconds);
  // Sim time in nanoseconds: 100 s.
  t = interpretPointTimes("timestamp", PointField::FLOAT64, {100e9, 100.05e9}, {},
                          ros::Time(100, 0));
  ASSERT_EQ(t.kind, PointTimeKind::kAbsoluteNanoseconds);
  EXPECT_NEAR(t.time_s[1], 0.05, 1e-7);
}

}  // namespace
}  // namespace node
}  // namespace gmm_localization
