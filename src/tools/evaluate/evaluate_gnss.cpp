#include "evaluate/evaluate_gnss.h"

#include <memory>
#include <ostream>
#include <sstream>

#include "gmm_localization/core/map/map_format.h"

namespace gmm_localization {
namespace eval {

Result<Georeference> mapGeoreference(const std::string& map_directory) {
  using R = Result<Georeference>;
  std::string dir = map_directory;
  while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
  auto manifest = readManifest(dir);
  if (!manifest) return R::failure(manifest.error());
  if (manifest->georeference.hasGrid()) return manifest->georeference;
  const size_t slash = dir.find_last_of('/');
  if (slash != std::string::npos && slash > 0) {
    auto parent = readManifest(dir.substr(0, slash));
    if (parent && parent->georeference.hasGrid()) return parent->georeference;
  }
  return R::failure("--gps: the map '" + map_directory +
                    "' has no georeference with a UTM zone, so a GNSS fix cannot be placed in "
                    "it; rebuild it with build_map --utm-zone ZONE --georef-origin E,N,U (for "
                    "simulate's drives: --utm-zone 17N --georef-origin 277000,4686000,250)");
}

Status attachGnss(const node::EkfNodeOptions& ekf, const std::string& map_directory,
                  LocalizerPipeline* pipeline, BagVisitor* visitor, EvaluationResults* out,
                  std::ostream& log) {
  if (!ekf.filter.gnss_enabled) return Status::success();
  auto georeference = mapGeoreference(map_directory);
  if (!georeference) return Status::failure(georeference.error());
  pipeline->setGeoreference(*georeference);
  out->info.gps = true;
  visitor->gnss_topic = ekf.gnss_topic;
  // As gnss_initializer:=true on the vehicle: while the filter is not running (no match started
  // it), the fixes' course over ground gives an initial pose for both nodelets (/initialpose).
  auto initializer = std::make_shared<GnssInitialPose>(GnssInitialPoseOptions{});
  const Georeference geo = *georeference;
  visitor->gnss = [pipeline, out, initializer, geo](const GnssFix& fix) {
    RunInfo& i = out->info;
    ++i.gnss_fixes;
    if (!pipeline->filter().active()) {
      auto e = initializer->addFix(geo, fix);
      if (e) {
        Pose6 p;
        p.x = e->x_m;
        p.y = e->y_m;
        p.z = e->z_m;
        p.yaw = e->yaw_rad;
        Matrix6d c = Matrix6d::Zero();
        const int idx[3] = {0, 1, 5};
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) c(idx[a], idx[b]) = e->cov_xy_yaw(a, b);
        }
        if (pipeline->setInitialPose(p, c, e->stamp_s, /*z_known=*/false)) {
          std::ostringstream note;
          note.precision(10);
          note << "GNSS initial pose at t = " << e->stamp_s << " s (" << e->heading_source
               << "), as gnss_initializer:=true";
          i.notes.push_back(note.str());
          initializer->reset();
        }
      }
    }
    const FuseReport r = pipeline->addGnss(fix);
    if (r.fused()) {
      ++i.gnss_fused;
    } else if (r.outcome == FuseOutcome::kRejectedGate) {
      ++i.gnss_gated;
    } else if (r.outcome == FuseOutcome::kRejectedNotInitialized) {
      ++i.gnss_filter_not_running;
    } else {
      ++i.gnss_refused;  // no solution (an outage), or not placeable in the map
    }
  };
  log << "GNSS fixes on " << ekf.gnss_topic << " into the EKF (map georeference "
      << georeference->describe() << ")" << std::endl;
  return Status::success();
}

}  // namespace eval
}  // namespace gmm_localization
