#include "gmm_localization/sim/kitti_writer.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <memory>

namespace gmm_localization {
namespace sim {

namespace {
void writePoseLine(std::FILE* f, const Eigen::Isometry3d& pose) {
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) std::fprintf(f, "%.9e%c", m(r, c), (r == 2 && c == 3) ? '\n' : ' ');
}
}  // namespace

Result<std::unique_ptr<KittiWriter>> KittiWriter::open(const std::string& dir, bool write_labels) {
  using R = Result<std::unique_ptr<KittiWriter>>;
  std::error_code ec;
  std::filesystem::create_directories(dir + "/velodyne", ec);
  if (ec) return R::failure("kitti: cannot create " + dir + "/velodyne: " + ec.message());
  if (write_labels) {
    std::filesystem::create_directories(dir + "/labels", ec);
    if (ec) return R::failure("kitti: cannot create " + dir + "/labels: " + ec.message());
  }
  std::unique_ptr<KittiWriter> w(new KittiWriter());
  w->dir_ = dir;
  w->labels_ = write_labels;
  w->poses_ = std::fopen((dir + "/poses.txt").c_str(), "w");
  w->times_ = std::fopen((dir + "/times.txt").c_str(), "w");
  if (!w->poses_ || !w->times_)
    return R::failure("kitti: cannot open poses.txt/times.txt in " + dir + ": " +
                      std::strerror(errno));
  return R(std::move(w));
}

KittiWriter::~KittiWriter() { close(); }

Status KittiWriter::writePoses(const std::string& path,
                               const std::vector<Eigen::Isometry3d>& poses) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return Status::failure("kitti: cannot open " + path + ": " + std::strerror(errno));
  for (const auto& p : poses) writePoseLine(f, p);
  if (std::fclose(f) != 0) return Status::failure("kitti: writing " + path + " failed");
  return Status::success();
}

Status KittiWriter::write(const std::vector<LidarPoint>& points, const Eigen::Isometry3d& pose,
                          double stamp) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06zu", count_);
  const std::string bin = dir_ + "/velodyne/" + name + ".bin";
  std::vector<float> buf(points.size() * 4);
  for (size_t i = 0; i < points.size(); ++i) {
    buf[4 * i] = points[i].x;
    buf[4 * i + 1] = points[i].y;
    buf[4 * i + 2] = points[i].z;
    buf[4 * i + 3] = points[i].intensity;
  }
  std::FILE* f = std::fopen(bin.c_str(), "wb");
  if (!f) return Status::failure("kitti: cannot open " + bin + ": " + std::strerror(errno));
  const size_t n = std::fwrite(buf.data(), sizeof(float), buf.size(), f);
  if (std::fclose(f) != 0 || n != buf.size())
    return Status::failure("kitti: short write to " + bin);
  if (labels_) {
    const std::string lab = dir_ + "/labels/" + name + ".label";
    std::vector<uint8_t> l(points.size());
    for (size_t i = 0; i < points.size(); ++i) l[i] = points[i].label;
    std::FILE* g = std::fopen(lab.c_str(), "wb");
    if (!g) return Status::failure("kitti: cannot open " + lab + ": " + std::strerror(errno));
    const size_t m = std::fwrite(l.data(), 1, l.size(), g);
    if (std::fclose(g) != 0 || m != l.size())
      return Status::failure("kitti: short write to " + lab);
  }
  writePoseLine(poses_, pose);
  std::fprintf(times_, "%.6f\n", stamp);
  ++count_;
  return Status::success();
}

Status KittiWriter::close() {
  bool ok = true;
  if (poses_) ok &= std::fclose(poses_) == 0;
  if (times_) ok &= std::fclose(times_) == 0;
  poses_ = times_ = nullptr;
  return ok ? Status::success()
            : Status::failure("kitti: closing poses.txt/times.txt in " + dir_ + " failed");
}

}  // namespace sim
}  // namespace gmm_localization
