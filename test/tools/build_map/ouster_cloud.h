#pragma once
// A PointCloud2 laid out like ouster_ros's, for the build_map tests.
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include <sensor_msgs/PointCloud2.h>
#include <Eigen/Core>

namespace gmm_localization {
namespace testing {

/// An Ouster-like cloud (ouster_ros's layout: x y z, intensity at 16, uint32 `t` [ns after the
/// stamp] at 20, uint16 reflectivity and ring, uint32 range; 48-byte points) of the given
/// points and times.
inline sensor_msgs::PointCloud2 ousterCloud(double stamp, const std::string& frame,
                                            const std::vector<Eigen::Vector3f>& points,
                                            const std::vector<uint32_t>& t_ns) {
  sensor_msgs::PointCloud2 c;
  c.header.stamp.fromSec(stamp);
  c.header.frame_id = frame;
  const std::pair<const char*, uint8_t> fields[] = {
      {"x", sensor_msgs::PointField::FLOAT32},   {"y", sensor_msgs::PointField::FLOAT32},
      {"z", sensor_msgs::PointField::FLOAT32},   {"intensity", sensor_msgs::PointField::FLOAT32},
      {"t", sensor_msgs::PointField::UINT32},    {"reflectivity", sensor_msgs::PointField::UINT16},
      {"ring", sensor_msgs::PointField::UINT16}, {"range", sensor_msgs::PointField::UINT32}};
  const uint32_t offsets[] = {0, 4, 8, 16, 20, 24, 26, 32};
  for (int k = 0; k < 8; ++k) {
    sensor_msgs::PointField f;
    f.name = fields[k].first;
    f.datatype = fields[k].second;
    f.offset = offsets[k];
    f.count = 1;
    c.fields.push_back(f);
  }
  c.height = 1;
  c.width = static_cast<uint32_t>(points.size());
  c.point_step = 48;
  c.row_step = c.point_step * c.width;
  c.data.assign(c.row_step, 0);
  for (size_t i = 0; i < points.size(); ++i) {
    uint8_t* p = c.data.data() + i * c.point_step;
    std::memcpy(p, points[i].data(), 12);
    std::memcpy(p + 20, &t_ns[i], 4);
  }
  return c;
}

}  // namespace testing
}  // namespace gmm_localization
