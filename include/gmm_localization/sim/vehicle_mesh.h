#pragma once
// Meshes of parked and moving vehicles and of pedestrians (simple boxes and prisms).

#include <Eigen/Core>

#include "gmm_localization/sim/mesh.h"
#include "gmm_localization/sim/random.h"

namespace gmm_localization {
namespace sim {

struct CarShape {
  double length_m = 4.6;
  double width_m = 1.8;
  double height_m = 1.5;
};

/// Sedan, SUV or van dimensions drawn from `rng`.
CarShape randomCarShape(Rng& rng);

/// Car standing on `ground_center` (centre of its footprint on the ground), heading `yaw_rad`.
void addCar(TriangleMesh& mesh, const Eigen::Vector3d& ground_center, double yaw_rad,
            const CarShape& shape, uint8_t label);

/// Pedestrian (about 1.75 m tall) standing on `ground_center`.
void addPedestrian(TriangleMesh& mesh, const Eigen::Vector3d& ground_center, uint8_t label);

}  // namespace sim
}  // namespace gmm_localization
