#pragma once
// TriangleMesh: the static world as triangles with a material and a ground-truth label per
// triangle, plus builders for the primitive shapes the town is made of. World frame: x east,
// y north, z up, metres.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "gmm_localization/sim/materials.h"

namespace gmm_localization {
namespace sim {

struct TriangleMesh {
  std::vector<float> vertices;      ///< x, y, z per vertex
  std::vector<uint32_t> indices;    ///< three vertex indices per triangle
  std::vector<Material> materials;  ///< one per triangle
  std::vector<uint8_t> labels;      ///< one PointLabel per triangle

  size_t numVertices() const { return vertices.size() / 3; }
  size_t numTriangles() const { return indices.size() / 3; }
  uint32_t addVertex(const Eigen::Vector3d& p);
  void addTriangle(uint32_t a, uint32_t b, uint32_t c, Material m, uint8_t label);
  void append(const TriangleMesh& other);
};

/// Builders. Each appends to `mesh`; `label` is a PointLabel.
struct MeshStyle {
  Material material = Material::kWall;
  uint8_t label = kLabelStatic;
};

/// Quad a-b-c-d (in order around its border).
void addQuad(TriangleMesh& mesh, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
             const Eigen::Vector3d& c, const Eigen::Vector3d& d, MeshStyle style);

/// Box with its bottom face centred at `base`, size (length along heading, width, height),
/// rotated by `yaw_rad` about z. `bottom` false omits the bottom face.
void addBox(TriangleMesh& mesh, const Eigen::Vector3d& base, const Eigen::Vector3d& size,
            double yaw_rad, MeshStyle style, bool bottom = false);

/// Vertical prism (n-gon cylinder) from `base` up by `height_m`.
void addPrism(TriangleMesh& mesh, const Eigen::Vector3d& base, double radius_m, double height_m,
              int sides, MeshStyle style);

/// Ellipsoid centred at `center` with semi-axes `radii`, from a once-subdivided octahedron
/// (32 triangles).
void addEllipsoid(TriangleMesh& mesh, const Eigen::Vector3d& center, const Eigen::Vector3d& radii,
                  MeshStyle style);

/// Regular grid surface over [x0,x1]x[y0,y1] with nx x ny cells and z = height(x, y).
template <typename HeightFn>
void addGridSurface(TriangleMesh& mesh, double x0, double x1, double y0, double y1, int nx, int ny,
                    HeightFn height, MeshStyle style) {
  const uint32_t first = static_cast<uint32_t>(mesh.numVertices());
  for (int j = 0; j <= ny; ++j) {
    const double y = y0 + (y1 - y0) * j / ny;
    for (int i = 0; i <= nx; ++i) {
      const double x = x0 + (x1 - x0) * i / nx;
      mesh.addVertex(Eigen::Vector3d(x, y, height(x, y)));
    }
  }
  const uint32_t row = static_cast<uint32_t>(nx + 1);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const uint32_t a = first + j * row + i;
      mesh.addTriangle(a, a + 1, a + row + 1, style.material, style.label);
      mesh.addTriangle(a, a + row + 1, a + row, style.material, style.label);
    }
  }
}

}  // namespace sim
}  // namespace gmm_localization
