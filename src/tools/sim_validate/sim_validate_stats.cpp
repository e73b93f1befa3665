#include "sim_validate/sim_validate_stats.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace tools {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

Result<std::vector<Eigen::Vector4f>> readPcdXyzi(const std::string& path) {
  using R = Result<std::vector<Eigen::Vector4f>>;
  std::ifstream in(path, std::ios::binary);
  if (!in) return R::failure("cannot open " + path);
  std::string line, fields, data;
  size_t points = 0;
  while (std::getline(in, line)) {
    if (line.rfind("FIELDS", 0) == 0) fields = line;
    if (line.rfind("POINTS", 0) == 0) points = std::stoul(line.substr(7));
    if (line.rfind("DATA", 0) == 0) {
      data = line;
      break;
    }
  }
  if (fields.find("x y z intensity") == std::string::npos)
    return R::failure(path + ": expected FIELDS x y z intensity, got '" + fields + "'");
  if (data.find("binary") == std::string::npos || data.find("compressed") != std::string::npos)
    return R::failure(path + ": only DATA binary is supported, got '" + data + "'");
  std::vector<Eigen::Vector4f> out(points);
  in.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(points * 16));
  if (static_cast<size_t>(in.gcount()) != points * 16)
    return R::failure(path + ": truncated point data");
  return out;
}

RevolutionStats revolutionStats(const std::vector<RevolutionPoint>& pts, size_t slots) {
  RevolutionStats s;
  s.points = pts.size();
  s.slots = slots;
  if (pts.empty()) return s;
  // RANSAC ground plane among points within 30 m and below the sensor.
  std::vector<int> cand;
  for (size_t i = 0; i < pts.size(); ++i)
    if (pts[i].p.norm() < 30.0f && pts[i].p.z() < -0.5f) cand.push_back(static_cast<int>(i));
  sim::Rng rng(12345);
  Eigen::Vector4d best(0, 0, 1, 0);
  size_t best_inliers = 0;
  for (int it = 0; it < 400 && cand.size() >= 3; ++it) {
    const Eigen::Vector3d a =
        pts[cand[rng.uniformInt(static_cast<int>(cand.size()))]].p.cast<double>();
    const Eigen::Vector3d b =
        pts[cand[rng.uniformInt(static_cast<int>(cand.size()))]].p.cast<double>();
    const Eigen::Vector3d c =
        pts[cand[rng.uniformInt(static_cast<int>(cand.size()))]].p.cast<double>();
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-6) continue;
    n.normalize();
    if (n.z() < 0) n = -n;
    if (n.z() < std::cos(25.0 * M_PI / 180.0)) continue;
    const double d = -n.dot(a);
    size_t inl = 0;
    for (int k : cand) inl += std::abs(n.dot(pts[k].p.cast<double>()) + d) < 0.08;
    if (inl > best_inliers) {
      best_inliers = inl;
      best << n, d;
    }
  }
  const Eigen::Vector3d n = best.head<3>();
  s.sensor_height_m = best[3];
  std::array<std::vector<double>, 8> ring_ranges;
  std::vector<double> ranges, intens;
  size_t ground = 0;
  for (const RevolutionPoint& q : pts) {
    const Eigen::Vector3d p = q.p.cast<double>();
    const double r = p.norm();
    ranges.push_back(r);
    intens.push_back(q.intensity);
    for (size_t b = 0; b + 1 < rangeBinEdges().size(); ++b)
      if (r >= rangeBinEdges()[b] && r < rangeBinEdges()[b + 1]) s.range_hist[b] += 1.0;
    if (std::abs(n.dot(p) + best[3]) < 0.15) {
      ++ground;
      if (q.ring >= 0 && q.ring < 8) ring_ranges[q.ring].push_back((p - n * n.dot(p)).norm());
    }
  }
  for (double& h : s.range_hist) h /= static_cast<double>(pts.size());
  s.ground_share = static_cast<double>(ground) / pts.size();
  for (int r = 0; r < 8; ++r)
    s.ring_ground_range[r] = ring_ranges[r].size() > 20 ? median(ring_ranges[r]) : 0.0;
  s.median_range_m = median(ranges);
  s.median_intensity = median(intens);
  double sum = 0.0;
  for (double i : intens) sum += i;
  s.mean_intensity = sum / intens.size();
  return s;
}

}  // namespace tools
}  // namespace gmm_localization
