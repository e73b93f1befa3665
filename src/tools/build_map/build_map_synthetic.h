#pragma once
// A synthetic street for measuring the map builder before the simulator lands: a straight
// street along +x, scanned like a 32-laser LIDAR (HDL-32E elevations) driving down it.
//
// World (seeded, deterministic): a crowned road |y| < 7 m (8 cm crown), curbs, 0.15 m
// sidewalks to |y| = 11 m; buildings 15-45 m long and 6-30 m tall with 0-3 m setbacks and 3-6 m
// alleys between them, a second row of buildings 40 m out; awnings at 2.8-3.0 m on 30% of
// facades; parked cars (boxes 4.4 x 1.8 m, 0.25-1.5 m high: the road shows under them) in 60%
// of 6 m slots on both sides; street trees every 12-20 m (0.15 m trunk, porous 2 m canopy:
// rays stop at an exponential depth, like foliage); poles every 35 m.
// Sensor: 32 lasers from +10.67 to -30.67 deg, azimuth step as configured, 1.95 m above the
// road in the right lane, one revolution every scan_spacing_m, 2 cm Gaussian range noise,
// 1-100 m range, no motion distortion; poses are exact (the map is built from ground truth).
// Intensities (for the reflectivity layer): asphalt 11 with 0.15 m lane lines of 110 (the
// centre line and both edge lines), concrete sidewalks 40, facades 60, cars 30, poles 50,
// trunks 20, foliage 25; the vehicle frame is base_link on the road under the sensor.

#include <memory>
#include <string>

#include "build_map/build_map_options.h"
#include "gmm_localization/core/mapping/point_batch.h"

namespace gmm_localization {
namespace tools {

class SyntheticStreetSource : public PointBatchSource {
 public:
  explicit SyntheticStreetSource(const SyntheticStreetOptions& options);
  ~SyntheticStreetSource() override;
  Result<bool> next(PointBatch& batch) override;
  size_t sizeHint() const override;
  std::string describe() const override;

 private:
  struct World;
  SyntheticStreetOptions options_;
  std::unique_ptr<World> world_;
  size_t next_ = 0;
};

}  // namespace tools
}  // namespace gmm_localization
