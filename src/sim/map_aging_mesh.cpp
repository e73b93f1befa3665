// Map aging: the meshes of construction fences, containers and grown crowns, and the shading
// of repaved road stretches.
#include <algorithm>
#include <cmath>

#include "gmm_localization/sim/map_aging.h"

namespace gmm_localization {
namespace sim {
namespace {

// Construction fence panels (the common 3.5 m x 2 m mesh panels, here opaque: urban sites hang
// screening fabric or banners on them).
constexpr double kPanelWidthM = 3.5;
constexpr double kPanelHeightM = 2.0;
constexpr double kPanelThicknessM = 0.05;
const MeshStyle kAgedMetal{Material::kMetal, kLabelDynamic};
constexpr double kFacetMean = 0.9;  // mean radius of addEllipsoid's facets / semi-axis

using Surface = std::function<double(double, double)>;

/// Lowest ground under the footprint's corners and centre: the object stands there (the part
/// below the higher ground is hidden in it, so no gap shows under the object).
double baseHeight(const Footprint& f, const Surface& surface) {
  const Eigen::Vector2d a(std::cos(f.yaw_rad), std::sin(f.yaw_rad)), b(-a.y(), a.x());
  double z = surface(f.center.x(), f.center.y());
  for (int sx = -1; sx <= 1; sx += 2) {
    for (int sy = -1; sy <= 1; sy += 2) {
      const Eigen::Vector2d p = f.center + a * (sx * f.half_length_m) + b * (sy * f.half_width_m);
      z = std::min(z, surface(p.x(), p.y()));
    }
  }
  return z;
}

void addContainer(TriangleMesh* mesh, const Footprint& f, const Surface& surface) {
  addBox(*mesh, Eigen::Vector3d(f.center.x(), f.center.y(), baseHeight(f, surface)),
         Eigen::Vector3d(kContainerLengthM, kContainerWidthM, kContainerHeightM), f.yaw_rad,
         kAgedMetal);
}

/// Panels along the edge from a to b; a panel crossing the kerb reaches from the lower ground
/// to 2 m above the higher one.
void addFenceEdge(TriangleMesh* mesh, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                  const Surface& surface) {
  const double len = (b - a).norm();
  const int n = std::max(1, static_cast<int>(std::ceil(len / kPanelWidthM)));
  const double yaw = std::atan2(b.y() - a.y(), b.x() - a.x());
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d p0 = a + (b - a) * (static_cast<double>(k) / n);
    const Eigen::Vector2d p1 = a + (b - a) * (static_cast<double>(k + 1) / n);
    const Eigen::Vector2d c = 0.5 * (p0 + p1);
    const double z0 = surface(p0.x(), p0.y()), z1 = surface(p1.x(), p1.y());
    const double zc = surface(c.x(), c.y());
    const double base = std::min({z0, z1, zc}) - 0.05;
    const double top = std::max({z0, z1, zc}) + kPanelHeightM;
    addBox(*mesh, Eigen::Vector3d(c.x(), c.y(), base),
           Eigen::Vector3d(len / n, kPanelThicknessM, top - base), yaw, kAgedMetal);
  }
}

void addFence(TriangleMesh* mesh, const Footprint& f, const Surface& surface) {
  const Eigen::Vector2d a(std::cos(f.yaw_rad), std::sin(f.yaw_rad)), b(-a.y(), a.x());
  const Eigen::Vector2d corners[4] = {f.center - a * f.half_length_m - b * f.half_width_m,
                                      f.center + a * f.half_length_m - b * f.half_width_m,
                                      f.center + a * f.half_length_m + b * f.half_width_m,
                                      f.center - a * f.half_length_m + b * f.half_width_m};
  for (int k = 0; k < 4; ++k) addFenceEdge(mesh, corners[k], corners[(k + 1) % 4], surface);
}

}  // namespace

void addMapAgingMesh(const Town& town, const MapAging& aging, const Surface& surface,
                     TriangleMesh* mesh) {
  for (const ConstructionSite& s : aging.sites) {
    addFence(mesh, s.fence, surface);
    if (s.has_container) addContainer(mesh, s.container, surface);
  }
  for (const Footprint& c : aging.containers) addContainer(mesh, c, surface);
  for (const GrownTree& g : aging.grown_trees) {
    // The new growth as one porous foliage shell around the old canopy: g further out and g
    // lower (semi-axes rh + g and rv + g/2, centre g/2 lower), top unchanged. The 32-triangle
    // ellipsoid's facets lie at 0.82-1.0 of its semi-axes (about 0.9 on average), hence the
    // division. Rays that pass the shell (foliage porosity) still reach the old blobs inside.
    const TreeCrown& t = town.trees()[g.tree];
    const double r = g.growth_m;
    const double h = (t.radius_h_m + r) / kFacetMean, v = (t.radius_v_m + 0.5 * r) / kFacetMean;
    addEllipsoid(*mesh, t.center - Eigen::Vector3d(0.0, 0.0, 0.5 * r), Eigen::Vector3d(h, h, v),
                 {Material::kFoliage, kLabelDynamic});
  }
}

Material roadSurfaceAt(const Town& town, const MapAging& aging, double x, double y) {
  const RepavedStretch* r = aging.repaved.empty() ? nullptr : aging.repavedAt(x, y);
  if (r == nullptr) return town.markingAt(x, y) ? Material::kLaneMarking : Material::kAsphalt;
  // Repainted lines sit paint_shift_m along `lateral`: the paint at (x, y) is the town's
  // pattern at (x, y) - shift.
  if (r->repainted &&
      town.markingAt(x - r->paint_shift_m * r->lateral.x(), y - r->paint_shift_m * r->lateral.y()))
    return Material::kLaneMarking;
  return Material::kAsphaltNew;
}

}  // namespace sim
}  // namespace gmm_localization
