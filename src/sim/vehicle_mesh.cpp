#include "gmm_localization/sim/vehicle_mesh.h"

#include <cmath>

namespace gmm_localization {
namespace sim {

CarShape randomCarShape(Rng& rng) {
  const double kind = rng.uniform();
  if (kind < 0.55) return {rng.uniform(4.2, 4.9), rng.uniform(1.75, 1.85), rng.uniform(1.40, 1.50)};
  if (kind < 0.9) return {rng.uniform(4.5, 5.0), rng.uniform(1.85, 1.95), rng.uniform(1.65, 1.80)};
  return {rng.uniform(5.0, 5.6), rng.uniform(1.95, 2.05), rng.uniform(1.95, 2.30)};
}

void addCar(TriangleMesh& mesh, const Eigen::Vector3d& ground_center, double yaw_rad,
            const CarShape& s, uint8_t label) {
  const double c = std::cos(yaw_rad), sn = std::sin(yaw_rad);
  auto at = [&](double fwd, double left, double up) -> Eigen::Vector3d {
    return ground_center + Eigen::Vector3d(c * fwd - sn * left, sn * fwd + c * left, up);
  };
  const double clearance = 0.28, body_top = clearance + 0.5 * s.height_m;
  addBox(mesh, at(0, 0, clearance), {s.length_m, s.width_m, body_top - clearance}, yaw_rad,
         {Material::kCarPaint, label}, true);
  // Cabin: windows all round, roof on top, set slightly back from the centre.
  const double cabin_len = 0.55 * s.length_m;
  addBox(mesh, at(-0.08 * s.length_m, 0, body_top),
         {cabin_len, s.width_m - 0.16, s.height_m - body_top}, yaw_rad,
         {Material::kCarGlass, label});
  addBox(mesh, at(-0.08 * s.length_m, 0, s.height_m - 0.06), {cabin_len, s.width_m - 0.14, 0.06},
         yaw_rad, {Material::kCarPaint, label});
  for (int k = 0; k < 4; ++k) {
    const double fwd = (k & 1 ? 0.33 : -0.33) * s.length_m;
    const double left = (k & 2 ? 0.5 : -0.5) * (s.width_m - 0.25);
    addBox(mesh, at(fwd, left, 0.0), {0.64, 0.22, clearance + 0.1}, yaw_rad,
           {Material::kTire, label});
  }
}

void addPedestrian(TriangleMesh& mesh, const Eigen::Vector3d& g, uint8_t label) {
  const MeshStyle style{Material::kPerson, label};
  addPrism(mesh, g + Eigen::Vector3d(0.0, 0.11, 0.0), 0.08, 0.85, 6, style);  // legs
  addPrism(mesh, g + Eigen::Vector3d(0.0, -0.11, 0.0), 0.08, 0.85, 6, style);
  addBox(mesh, g + Eigen::Vector3d(0, 0, 0.85), {0.28, 0.44, 0.62}, 0.0, style, true);  // torso
  addPrism(mesh, g + Eigen::Vector3d(0, 0, 1.47), 0.1, 0.26, 6, style);                 // head
}

}  // namespace sim
}  // namespace gmm_localization
