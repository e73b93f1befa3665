#include "bench_peers.h"

#include <chrono>

#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/ndt.h>

namespace gmm_localization {
namespace bench {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

struct PeerMatcher::Impl {
  Kind kind;
  PeerOptions options;
  pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ> ndt;
  pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
};

namespace {
Cloud::Ptr toCloud(const PointList& pts) {
  Cloud::Ptr c(new Cloud);
  c->reserve(pts.size());
  for (const Eigen::Vector3f& p : pts) {
    if (p.allFinite()) c->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  return c;
}
}  // namespace

PeerMatcher::PeerMatcher(Kind kind, const PeerOptions& options) : impl_(new Impl) {
  impl_->kind = kind;
  impl_->options = options;
  impl_->ndt.setResolution(static_cast<float>(options.ndt_resolution_m));
  impl_->ndt.setStepSize(options.ndt_step_size_m);
  impl_->ndt.setTransformationEpsilon(options.ndt_epsilon);
  impl_->ndt.setMaximumIterations(options.max_iterations);
  impl_->gicp.setMaxCorrespondenceDistance(options.gicp_max_correspondence_m);
  impl_->gicp.setTransformationEpsilon(options.epsilon * 0.1);
  impl_->gicp.setMaximumIterations(options.max_iterations);
}

PeerMatcher::~PeerMatcher() { delete impl_; }

std::string PeerMatcher::name() const { return impl_->kind == Kind::kNdt ? "PCL NDT" : "PCL GICP"; }

void PeerMatcher::setTarget(const PointList& map_points) {
  Cloud::Ptr target = toCloud(map_points);
  if (impl_->kind == Kind::kNdt) {
    impl_->ndt.setInputTarget(target);
  } else {
    impl_->gicp.setInputTarget(target);
  }
}

PeerResult PeerMatcher::align(const PointList& scan, const Eigen::Isometry3d& guess) {
  const auto t0 = std::chrono::steady_clock::now();
  Cloud::Ptr source = toCloud(voxelDownsample(scan, impl_->options.source_voxel_m));
  Cloud aligned;
  PeerResult r;
  const Eigen::Matrix4f g = guess.matrix().cast<float>();
  if (impl_->kind == Kind::kNdt) {
    impl_->ndt.setInputSource(source);
    impl_->ndt.align(aligned, g);
    r.pose.matrix() = impl_->ndt.getFinalTransformation().cast<double>();
    r.converged = impl_->ndt.hasConverged();
  } else {
    impl_->gicp.setInputSource(source);
    impl_->gicp.align(aligned, g);
    r.pose.matrix() = impl_->gicp.getFinalTransformation().cast<double>();
    r.converged = impl_->gicp.hasConverged();
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace bench
}  // namespace gmm_localization
