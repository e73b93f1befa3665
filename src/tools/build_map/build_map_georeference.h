#pragma once
// build_map's georeference options -> the map's Georeference (core/map/georeference.h).
//
//   --offset E,N,U        the input is in grid coordinates: subtracted from every point, and the
//                         map origin is there;
//   --georef-origin E,N,U the input is already in the map frame, whose origin is there;
//   --mgrs-origin REF[,U] as --georef-origin, the origin an MGRS reference (it names the zone);
//   --utm-zone ZONE / --epsg CODE  the grid (17N, EPSG:32617, ...);
//   --datum TEXT          free text kept with the map (a zone named in it is used when no other
//                         option names one).
// One origin option at most; the zones named must agree; an origin without a zone is kept as a
// text-only georeference (map_info says so; GNSS cannot use it).

#include <optional>
#include <string>

#include <Eigen/Core>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/georeference.h"

namespace gmm_localization {
namespace tools {

struct GeoreferenceArgs {
  std::optional<Eigen::Vector3d> offset_m;         ///< --offset
  std::optional<Eigen::Vector3d> georef_origin_m;  ///< --georef-origin
  std::string mgrs_origin;                         ///< --mgrs-origin
  std::string utm_zone;                            ///< --utm-zone
  std::string epsg;                                ///< --epsg
  std::string datum;                               ///< --datum
};

/// The georeference, or which options conflict or are wrong.
Result<Georeference> resolveGeoreference(const GeoreferenceArgs& args);

}  // namespace tools
}  // namespace gmm_localization
