// build_map input: a PCD point-cloud map, read with PCL.
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include "build_map/build_map_readers.h"

namespace gmm_localization {
namespace tools {

struct PcdSource::Impl {
  std::string path;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  size_t batch_points = 0;
  size_t next = 0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
};

PcdSource::~PcdSource() = default;

Result<std::unique_ptr<PcdSource>> PcdSource::open(const std::string& path, size_t batch_points,
                                                   const Eigen::Vector3d& offset_m) {
  using R = Result<std::unique_ptr<PcdSource>>;
  auto src = std::unique_ptr<PcdSource>(new PcdSource());
  src->impl_ = std::make_unique<Impl>();
  src->impl_->path = path;
  src->impl_->batch_points = std::max<size_t>(batch_points, 1);
  src->impl_->offset = offset_m;
  pcl::PCDReader reader;
  pcl::PCLPointCloud2 header;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0, type = 0;
  unsigned int offset = 0;
  if (reader.readHeader(path, header, origin, orientation, version, type, offset) != 0) {
    return R::failure("PCD file '" + path + "': cannot read its header (missing or not a PCD)");
  }
  bool x = false, y = false, z = false;
  for (const auto& f : header.fields) {
    x = x || f.name == "x";
    y = y || f.name == "y";
    z = z || f.name == "z";
  }
  if (!x || !y || !z) return R::failure("PCD file '" + path + "': no x, y and z fields");
  if (reader.read(path, src->impl_->cloud) != 0) {
    return R::failure("PCD file '" + path + "': PCL could not read the points");
  }
  return R(std::move(src));
}

Result<bool> PcdSource::next(PointBatch& batch) {
  batch.clear();
  Impl& m = *impl_;
  if (m.next >= m.cloud.size()) return false;
  const size_t end = std::min(m.cloud.size(), m.next + m.batch_points);
  batch.points_m.reserve(end - m.next);
  for (size_t i = m.next; i < end; ++i) {
    const auto& p = m.cloud[i];
    batch.points_m.emplace_back(static_cast<float>(p.x - m.offset.x()),
                                static_cast<float>(p.y - m.offset.y()),
                                static_cast<float>(p.z - m.offset.z()));
  }
  m.next = end;
  return true;
}

size_t PcdSource::sizeHint() const {
  return (impl_->cloud.size() + impl_->batch_points - 1) / impl_->batch_points;
}

size_t PcdSource::points() const { return impl_->cloud.size(); }

std::string PcdSource::describe() const {
  return "PCD map '" + impl_->path + "' (" + std::to_string(impl_->cloud.size()) + " points)";
}

}  // namespace tools
}  // namespace gmm_localization
