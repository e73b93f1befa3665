#pragma once
// Bad clouds for the rostests (matcher_ekf_nodelets_test.cpp, vehicle_bad_input_test.cpp): each
// spoils a good scan message, with the text its MatchStatus reason must contain.
#include <cmath>
#include <cstring>
#include <functional>
#include <vector>

#include <sensor_msgs/PointCloud2.h>

namespace gmm_localization {
namespace node {

struct CloudCase {
  const char* what;
  std::function<void(sensor_msgs::PointCloud2&)> spoil;
  const char* reason;  ///< expected in the status's reason; nullptr: may be accepted
};

/// Writes float `v` into the x, y, z (the first 12 bytes) of every `every`-th point.
inline void setPoints(sensor_msgs::PointCloud2& m, float v, size_t every) {
  for (size_t i = 0; i * m.point_step + 12 <= m.data.size(); i += every) {
    for (int k = 0; k < 3; ++k) std::memcpy(&m.data[i * m.point_step + 4 * k], &v, 4);
  }
}

/// The clouds nothing can be matched in: a missing field, truncated data, empty, all NaN.
inline std::vector<CloudCase> unmatchableClouds() {
  return {
      {"no z field", [](sensor_msgs::PointCloud2& m) { m.fields[2].name = "w"; },
       "malformed cloud"},
      {"truncated data", [](sensor_msgs::PointCloud2& m) { m.data.resize(m.data.size() / 2); },
       "malformed cloud"},
      {"empty",
       [](sensor_msgs::PointCloud2& m) {
         m.width = 0;
         m.row_step = 0;
         m.data.clear();
       },
       "empty cloud"},
      {"all NaN", [](sensor_msgs::PointCloud2& m) { setPoints(m, std::nanf(""), 1); },
       "no finite points"},
  };
}

}  // namespace node
}  // namespace gmm_localization
