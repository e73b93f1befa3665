#include "gmm_localization/core/mapping/kitti_source.h"

#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "gmm_localization/core/map/map_format.h"

namespace gmm_localization {
namespace {

bool isFile(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

std::string padded(int i) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%06d", i);
  return buf;
}

Eigen::Isometry3d fromRows(const double* v) {
  Eigen::Matrix3d r;
  r << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();  // re-orthonormalised
  t.translation() = Eigen::Vector3d(v[3], v[7], v[11]);
  return t;
}

std::vector<std::string> tokens(const std::string& line) {
  std::istringstream s(line);
  std::vector<std::string> out;
  for (std::string t; s >> t;) out.push_back(t);
  return out;
}

bool toDoubles(const std::vector<std::string>& tok, size_t from, double* out) {
  for (size_t i = from; i < tok.size(); ++i) {
    char* end = nullptr;
    out[i - from] = std::strtod(tok[i].c_str(), &end);
    if (end == tok[i].c_str() || *end != '\0' || !std::isfinite(out[i - from])) return false;
  }
  return true;
}

}  // namespace

Result<std::map<int, Eigen::Isometry3d>> readKittiPoses(const std::string& path) {
  using R = Result<std::map<int, Eigen::Isometry3d>>;
  std::ifstream in(path);
  if (!in) return R::failure("poses file '" + path + "': cannot open (missing?)");
  std::map<int, Eigen::Isometry3d> poses;
  int row = 0, line_no = 0, format = 0;  // 1: KITTI 3x4, 2: graph
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    const auto tok = tokens(line);
    if (tok.empty() || tok[0][0] == '#') continue;
    const std::string where = "poses file '" + path + "' line " + std::to_string(line_no);
    double v[12];
    if (tok.size() == 12 && format != 2) {
      format = 1;
      if (!toDoubles(tok, 0, v)) return R::failure(where + ": not 12 numbers");
      poses[row++] = fromRows(v);
    } else if (tok.size() == 8 && format != 1) {
      format = 2;
      const size_t digits = tok[0].find_first_of("0123456789");
      char* end = nullptr;
      const long id =
          digits == std::string::npos ? -1 : std::strtol(tok[0].c_str() + digits, &end, 10);
      if (id < 0 || id > 100000000 || *end != '\0')
        return R::failure(where + ": bad id '" + tok[0] + "'");
      if (!toDoubles(tok, 1, v)) return R::failure(where + ": not 7 numbers after the id");
      Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
      if (!(q.norm() > 1e-6)) return R::failure(where + ": zero quaternion");
      Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
      t.linear() = q.normalized().toRotationMatrix();
      t.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
      if (!poses.emplace(static_cast<int>(id), t).second) {
        return R::failure(where + ": scan " + std::to_string(id) + " has two poses");
      }
    } else {
      return R::failure(where + ": expected 12 numbers (KITTI 3x4) or 'id x y z qx qy qz qw'" +
                        (format ? " like the lines before" : ""));
    }
  }
  if (poses.empty()) return R::failure("poses file '" + path + "': no pose");
  return poses;
}

Result<Eigen::Isometry3d> readKittiCalibTr(const std::string& path) {
  using R = Result<Eigen::Isometry3d>;
  std::ifstream in(path);
  if (!in) return R::failure("calibration file '" + path + "': cannot open (missing?)");
  for (std::string line; std::getline(in, line);) {
    const auto tok = tokens(line);
    double v[12];
    if (tok.size() == 13 && tok[0] == "Tr:") {
      if (!toDoubles(tok, 1, v)) return R::failure("calibration file '" + path + "': bad Tr line");
      return fromRows(v);
    }
  }
  return R::failure("calibration file '" + path + "': no 'Tr:' line with 12 numbers");
}

Result<std::vector<Eigen::Vector3f>> readKittiScan(const std::string& path, KittiFields fields,
                                                   std::vector<float>* intensity) {
  using R = Result<std::vector<Eigen::Vector3f>>;
  auto bytes = readFileBytes(path, uint64_t{1} << 31);
  if (!bytes) return R::failure("scan " + bytes.error());
  const size_t n = bytes->size();
  if (fields == KittiFields::kAuto) {
    const bool by16 = n % 16 == 0, by12 = n % 12 == 0;
    if (by16 && by12) {
      return R::failure("scan file '" + path + "': " + std::to_string(n) +
                        " bytes fits both x,y,z (12 B) and x,y,z,intensity (16 B) records: "
                        "give the layout explicitly");
    }
    if (!by16 && !by12) {
      return R::failure("scan file '" + path + "': " + std::to_string(n) +
                        " bytes is a multiple of neither 12 (xyz) nor 16 (xyzi) bytes");
    }
    fields = by16 ? KittiFields::kXyzi : KittiFields::kXyz;
  }
  const size_t stride = fields == KittiFields::kXyzi ? 16 : 12;
  if (n % stride != 0) {
    return R::failure("scan file '" + path + "': " + std::to_string(n) +
                      " bytes is not a multiple of " + std::to_string(stride) + " (" +
                      (stride == 16 ? "xyzi" : "xyz") + " records)");
  }
  std::vector<Eigen::Vector3f> points(n / stride);
  const bool with_intensity = intensity != nullptr && stride == 16;
  if (intensity) intensity->assign(with_intensity ? points.size() : 0, 0.f);
  auto floatAt = [](const uint8_t* b) {
    const uint32_t bits =
        uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  };
  const uint8_t* p = bytes->data();
  for (size_t i = 0; i < points.size(); ++i, p += stride) {
    for (int k = 0; k < 3; ++k) points[i][k] = floatAt(p + 4 * k);
    if (with_intensity) (*intensity)[i] = floatAt(p + 12);
  }
  return points;
}

Result<std::vector<int>> parseIndexList(const std::string& text) {
  using R = Result<std::vector<int>>;
  // The list as a whole, not each range, is bounded (60 ranges of 10^7 indices were 2.4 GB);
  // the text is quoted only in part, as it may be that long.
  const std::string list =
      "index list '" + (text.size() > 64 ? text.substr(0, 61) + "..." : text) + "'";
  std::vector<int> out;
  std::stringstream s(text);
  for (std::string item; std::getline(s, item, ',');) {
    int a = 0, b = 0;
    char tail = 0;
    int64_t count = 0;  // indices of the item
    if (std::sscanf(item.c_str(), "%d-%d%c", &a, &b, &tail) == 2 && a >= 0 && b >= a) {
      count = int64_t{b} - a + 1;
    } else if (std::sscanf(item.c_str(), "%d%c", &a, &tail) == 1 && a >= 0) {
      b = a;
      count = 1;
    } else {
      return R::failure(list + ": cannot read '" + item + "' (expected N or N-M, N >= 0)");
    }
    if (count > static_cast<int64_t>(kMaxIndexListSize - out.size())) {
      return R::failure(list + " holds more than " + std::to_string(kMaxIndexListSize) +
                        " indices (" + std::to_string(out.size()) + " before '" + item +
                        "', which adds " + std::to_string(count) + ")");
    }
    // In int64: a range ending at INT_MAX must not overflow the loop variable.
    for (int64_t i = a; i <= b; ++i) out.push_back(static_cast<int>(i));
  }
  if (out.empty()) return R::failure(list + " is empty");
  return out;
}

Result<std::unique_ptr<KittiScanSource>> KittiScanSource::open(const KittiSourceOptions& o) {
  using R = Result<std::unique_ptr<KittiScanSource>>;
  KittiSourceOptions opts = o;
  // A KITTI odometry sequence (or the simulator's KITTI output) keeps its scans in velodyne/.
  struct stat st;
  const std::string velodyne = o.scans_directory + "/velodyne";
  const bool nested_layout = ::stat(velodyne.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
  if (nested_layout) {
    opts.scans_directory = velodyne;
    if (opts.fields == KittiFields::kAuto) opts.fields = KittiFields::kXyzi;  // KITTI's layout
  }
  std::string poses_path = o.poses_file;
  if (poses_path.empty()) {
    poses_path = o.scans_directory + "/graph.txt";
    if (!isFile(poses_path)) poses_path = o.scans_directory + "/poses.txt";
  }
  auto poses = readKittiPoses(poses_path);
  if (!poses) return R::failure(poses.error());
  auto src = std::unique_ptr<KittiScanSource>(new KittiScanSource());
  src->options_ = opts;
  src->options_.poses_file = poses_path;
  auto resolve = [&](int i) {
    const std::string flat = opts.scans_directory + "/" + padded(i) + ".bin";
    if (isFile(flat)) return flat;
    const std::string nested = opts.scans_directory + "/" + padded(i) + "/points.bin";
    return isFile(nested) ? nested : std::string();
  };
  std::vector<int> wanted = o.scans;
  if (wanted.empty()) {
    for (const auto& entry : *poses) {
      if (!resolve(entry.first).empty()) wanted.push_back(entry.first);
    }
    if (wanted.empty()) {
      return R::failure("scan directory '" + opts.scans_directory +
                        "': no NNNNNN.bin or "
                        "NNNNNN/points.bin matches a pose in '" +
                        poses_path + "'");
    }
  }
  for (int i : wanted) {
    auto pose = poses->find(i);
    if (pose == poses->end())
      return R::failure("scan " + std::to_string(i) + ": no pose in '" + poses_path + "'");
    const std::string path = resolve(i);
    if (path.empty()) {
      return R::failure("scan " + std::to_string(i) + ": neither " + padded(i) + ".bin nor " +
                        padded(i) + "/points.bin in '" + opts.scans_directory + "'");
    }
    src->scans_.push_back({i, path, o.map_T_world * pose->second * o.pose_T_sensor});
  }
  return R(std::move(src));
}

Result<bool> KittiScanSource::next(PointBatch& batch) {
  batch.clear();
  if (next_ >= scans_.size()) return false;
  const Scan& scan = scans_[next_++];
  // NNNNNN/points.bin is the keyframe dumps' layout: x, y, z records.
  const std::string keyframe = "/points.bin";
  const bool is_keyframe =
      scan.path.size() >= keyframe.size() &&
      scan.path.compare(scan.path.size() - keyframe.size(), keyframe.size(), keyframe) == 0;
  const KittiFields fields =
      options_.fields == KittiFields::kAuto && is_keyframe ? KittiFields::kXyz : options_.fields;
  auto points = readKittiScan(scan.path, fields, &batch.intensity);
  if (!points) return Result<bool>::failure(points.error());
  setBatchFromSensorFrame(*points, scan.map_T_sensor, batch);
  batch.has_vehicle_origin = true;  // the scans' frame (see the class comment)
  batch.vehicle_origin_m = scan.map_T_sensor.translation();
  return true;
}

std::string KittiScanSource::describe() const {
  return "KITTI scans '" + options_.scans_directory + "' (" + std::to_string(scans_.size()) +
         " scans, poses '" + options_.poses_file + "')";
}

}  // namespace gmm_localization
