#pragma once
// A gtest fixture with the synthetic street (SyntheticWorld seed 42), its Gaussian mixture map
// and the chunks the registration searches (support/street_map.h), built once per test suite.

#include <memory>

#include <gtest/gtest.h>

#include "support/street_map.h"
#include "support/synthetic_world.h"

namespace gmm_localization {
namespace testing {

class StreetFixture : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    world_ = std::make_unique<SyntheticWorld>(42);
    gmm_ = std::make_unique<GmmMap>(world_->buildMap(streetGeometry(), 1));
    chunks_ = std::make_unique<ChunkMap>(rasterizeStreet(*gmm_));
  }
  static void TearDownTestSuite() {
    chunks_.reset();
    gmm_.reset();
    world_.reset();
  }
  static inline std::unique_ptr<SyntheticWorld> world_;
  static inline std::unique_ptr<GmmMap> gmm_;
  static inline std::unique_ptr<ChunkMap> chunks_;
};

}  // namespace testing
}  // namespace gmm_localization
