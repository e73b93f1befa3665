// Fuzz target: the PointCloud2 reader (node::fromMsg, ros/cloud_conversion.h) that the matcher
// and the cloud merger run on every received LIDAR cloud. The input chooses every field of the
// message: fields (names, offsets, datatypes, counts), point_step, row_step, width, height,
// is_bigendian and the data (layout: fuzz_input.h). An accepted cloud must have one point per
// width x height and each optional channel empty or of that size; written back with toMsg it
// must read again to the same points.
#include <cmath>
#include <cstdint>

#include "fuzz_check.h"
#include "fuzz_input.h"
#include "gmm_localization/ros/cloud_conversion.h"

namespace {

using namespace gmm_localization;

bool samePoint(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  for (int k = 0; k < 3; ++k) {
    if (!(a[k] == b[k] || (std::isnan(a[k]) && std::isnan(b[k])))) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Reader r(data, size);
  const sensor_msgs::PointCloud2 msg = fuzz::readCloud(r);
  auto cloud = node::fromMsg(msg);
  if (!cloud) return 0;
  const size_t n = size_t{msg.width} * msg.height;
  FUZZ_CHECK(cloud->points.size() == n, "%zu points for %zu", cloud->points.size(), n);
  FUZZ_CHECK(cloud->time_s.empty() || cloud->time_s.size() == n, "time channel");
  FUZZ_CHECK(cloud->intensity.empty() || cloud->intensity.size() == n, "intensity channel");
  FUZZ_CHECK(cloud->ring.empty() || cloud->ring.size() == n, "ring channel");
  FUZZ_CHECK(cloud->label.empty() || cloud->label.size() == n, "label channel");

  sensor_msgs::PointCloud2 out;
  node::toMsg(*cloud, out, "likelihood", std::vector<float>(n, 0.5f));
  auto again = node::fromMsg(out);
  FUZZ_CHECK(again.ok(), "toMsg's cloud does not read: %s", again.error().c_str());
  FUZZ_CHECK(again->points.size() == n, "point count changed");
  for (size_t i = 0; i < n; ++i) {
    FUZZ_CHECK(samePoint(again->points[i], cloud->points[i]), "point %zu changed", i);
  }
  FUZZ_CHECK(again->ring == cloud->ring && again->label == cloud->label, "ring/label changed");
  return 0;
}
