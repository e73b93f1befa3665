#pragma once
// Test support: the georeference the simulator places its worlds in by default (UTM 17N, origin
// E 277000 m, N 4686000 m, 250 m up: simulate --georef-origin), for tests of GNSS positions.

#include "gmm_localization/core/map/georeference.h"

namespace gmm_localization {
namespace testing {

inline Georeference simulatorGeoreference() {
  Georeference g;
  g.present = true;
  g.utm_zone = 17;
  g.utm_north = true;
  g.origin_easting_m = 277000.0;
  g.origin_northing_m = 4686000.0;
  g.origin_up_m = 250.0;
  return g;
}

}  // namespace testing
}  // namespace gmm_localization
