#pragma once
// The reflectivity layer: Levinson and Thrun's orthographic ground-reflectivity map (the
// baseline of the paper's Table I) through the height map's own machinery.
//
// A reflectivity map is a Gaussian mixture map whose cells hold mixtures over the intensity of
// the ground returns that fell in them instead of over height: each ground return contributes
// the value v = intensity * metres_per_unit in place of its z. Everything downstream is then
// unchanged: the builder's blur and EM (Levinson keeps one Gaussian per cell, mean and
// variance; a mixture of up to K_max components also covers a cell half on paint), the tiles,
// the map server, the rasterized multiresolution tables and the exact branch-and-bound (the
// paper notes in IV that the rasterized search serves Levinson's probabilistic maps too), the
// certificate and the EKF. The search runs over x, y and heading only: a reflectivity scan is
// levelled by the prior's roll and pitch, its z is the value v (independent of the pose), and
// the refinement leaves z, roll and pitch to the prior.
//
// Ground returns: a point whose height above the ground under the vehicle, after levelling
// (in the map frame: its z minus the vehicle frame's z minus ground_height_m), lies in
// [ground_min_m, ground_max_m], within max_range_m of the vehicle. A documented
// simplification of Levinson and Thrun's ground-plane fit: on a road that bends up or down
// beyond the band within max_range_m, far ground is left out (in the map and in the scans
// alike). No per-beam intensity calibration (Levinson and Thrun 2010 learn one per laser): the
// simulator's lasers share one response; real sensors with per-beam gains need it first.
//
// The scale: intensities are 0..255; at 0.02 m per unit the values span 0..5.1 m, asphalt
// (about 11) sits near 0.22 m and lane paint (about 110) near 2.2 m, and the map's 3 cm sigma
// floor is 1.5 intensity units: the height machinery's bins, blur and floors fit as they are.

#include <cmath>
#include <string>

namespace gmm_localization {

/// The layer a map holds (its manifest says which; maps before format version 3 are height).
enum class MapLayer : unsigned char { kHeight = 0, kReflectivity = 1 };

/// "height" or "reflectivity".
inline const char* mapLayerName(MapLayer layer) {
  return layer == MapLayer::kReflectivity ? "reflectivity" : "height";
}

struct ReflectivityLayerOptions {
  double metres_per_unit = 0.02;  ///< value = intensity * this [m per intensity unit]
  double ground_height_m = 0.0;   ///< z of the ground in the vehicle frame (base_link: 0)
  double ground_min_m = -0.3;     ///< ground band around that height [m]
  double ground_max_m = 0.3;
  double max_range_m = 40.0;  ///< horizontal range of the ground returns used [m]

  /// The value of a return of this intensity.
  float value(float intensity) const { return static_cast<float>(intensity * metres_per_unit); }
  /// True for a ground return: height above the vehicle frame (levelled, [m]) and horizontal
  /// range from it [m].
  bool isGround(double levelled_z_m, double range_xy_m) const {
    const double h = levelled_z_m - ground_height_m;
    return std::isfinite(h) && h >= ground_min_m && h <= ground_max_m && range_xy_m <= max_range_m;
  }
};

/// Empty when the options are within the bounds the map builder and the manifest accept, else
/// the first offending field, its value and the allowed range: metres_per_unit in (0, 100],
/// ground_height_m in [-100, 100] m, ground_min_m < ground_max_m both in [-10, 10] m,
/// max_range_m in (0, 1000] m (all finite).
std::string checkReflectivityLayer(const ReflectivityLayerOptions& options);

/// One line, e.g. "value = intensity x 0.02 m; ground: [-0.3, 0.3] m around z = 0 m of the
/// vehicle frame, within 40 m".
std::string describeReflectivityLayer(const ReflectivityLayerOptions& options);

}  // namespace gmm_localization
