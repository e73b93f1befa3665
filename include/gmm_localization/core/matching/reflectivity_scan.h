#pragma once
// A scan as the reflectivity layer sees it (core/map/reflectivity_layer.h): its ground returns,
// levelled by the vehicle's roll and pitch, each with the value of its intensity as z. Such
// points register against a reflectivity map with the same Registration as a height scan,
// searching x, y and heading: the request's prior then has z, roll and pitch 0 (the points are
// levelled and their z does not move with the pose), and the refinement climbs over x, y and
// heading only.

#include <string>
#include <vector>

#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/map/reflectivity_layer.h"
#include "gmm_localization/core/matching/registration.h"

namespace gmm_localization {

/// The ground returns of `base_points` (base_link [m], one intensity per point) levelled by
/// roll and pitch [rad] (as filterScan levels), as (x, y, value). Points with a non-finite
/// coordinate or intensity are left out. Empty when `intensity` does not match the points.
PointList reflectivityPoints(const PointList& base_points, const std::vector<float>& intensity,
                             double roll_rad, double pitch_rad,
                             const ReflectivityLayerOptions& options);

/// The registration options of the reflectivity layer, from the height layer's: no height
/// pre-alignment; a refinement over x, y and heading only; no obstacle labels (they compare
/// heights); the scan filter's height band spans every value, its ground bias is off (every
/// point is ground) and its voxels keep x and y at the height layer's size.
RegistrationOptions reflectivityRegistrationOptions(const RegistrationOptions& height);

}  // namespace gmm_localization
