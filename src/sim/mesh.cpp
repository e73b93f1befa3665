#include "gmm_localization/sim/mesh.h"

#include <array>
#include <cmath>

namespace gmm_localization {
namespace sim {

uint32_t TriangleMesh::addVertex(const Eigen::Vector3d& p) {
  vertices.push_back(static_cast<float>(p.x()));
  vertices.push_back(static_cast<float>(p.y()));
  vertices.push_back(static_cast<float>(p.z()));
  return static_cast<uint32_t>(numVertices() - 1);
}

void TriangleMesh::addTriangle(uint32_t a, uint32_t b, uint32_t c, Material m, uint8_t label) {
  indices.push_back(a);
  indices.push_back(b);
  indices.push_back(c);
  materials.push_back(m);
  labels.push_back(label);
}

void TriangleMesh::append(const TriangleMesh& other) {
  const uint32_t offset = static_cast<uint32_t>(numVertices());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  for (uint32_t i : other.indices) indices.push_back(i + offset);
  materials.insert(materials.end(), other.materials.begin(), other.materials.end());
  labels.insert(labels.end(), other.labels.begin(), other.labels.end());
}

void addQuad(TriangleMesh& mesh, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
             const Eigen::Vector3d& c, const Eigen::Vector3d& d, MeshStyle style) {
  const uint32_t ia = mesh.addVertex(a), ib = mesh.addVertex(b), ic = mesh.addVertex(c),
                 id = mesh.addVertex(d);
  mesh.addTriangle(ia, ib, ic, style.material, style.label);
  mesh.addTriangle(ia, ic, id, style.material, style.label);
}

void addBox(TriangleMesh& mesh, const Eigen::Vector3d& base, const Eigen::Vector3d& size,
            double yaw_rad, MeshStyle style, bool bottom) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const double hl = 0.5 * size.x(), hw = 0.5 * size.y();
  std::array<uint32_t, 8> v;
  for (int k = 0; k < 8; ++k) {
    const double lx = (k & 1) ? hl : -hl;
    const double ly = (k & 2) ? hw : -hw;
    const double z = (k & 4) ? size.z() : 0.0;
    v[k] = mesh.addVertex(base + Eigen::Vector3d(c * lx - s * ly, s * lx + c * ly, z));
  }
  auto quad = [&](int a, int b, int cc, int d) {
    mesh.addTriangle(v[a], v[b], v[cc], style.material, style.label);
    mesh.addTriangle(v[a], v[cc], v[d], style.material, style.label);
  };
  quad(0, 1, 5, 4);  // -y side
  quad(1, 3, 7, 5);  // +x side
  quad(3, 2, 6, 7);  // +y side
  quad(2, 0, 4, 6);  // -x side
  quad(4, 5, 7, 6);  // top
  if (bottom) quad(0, 2, 3, 1);
}

void addPrism(TriangleMesh& mesh, const Eigen::Vector3d& base, double radius_m, double height_m,
              int sides, MeshStyle style) {
  const uint32_t first = static_cast<uint32_t>(mesh.numVertices());
  for (int k = 0; k < sides; ++k) {
    const double a = 2.0 * M_PI * k / sides;
    const Eigen::Vector3d off(radius_m * std::cos(a), radius_m * std::sin(a), 0.0);
    mesh.addVertex(base + off);
    mesh.addVertex(base + off + Eigen::Vector3d(0, 0, height_m));
  }
  const uint32_t top_center = mesh.addVertex(base + Eigen::Vector3d(0, 0, height_m));
  for (int k = 0; k < sides; ++k) {
    const uint32_t b0 = first + 2 * k, t0 = b0 + 1;
    const uint32_t b1 = first + 2 * ((k + 1) % sides), t1 = b1 + 1;
    mesh.addTriangle(b0, b1, t1, style.material, style.label);
    mesh.addTriangle(b0, t1, t0, style.material, style.label);
    mesh.addTriangle(t0, t1, top_center, style.material, style.label);
  }
}

void addEllipsoid(TriangleMesh& mesh, const Eigen::Vector3d& center, const Eigen::Vector3d& radii,
                  MeshStyle style) {
  // Octahedron faces, each split into 4 with midpoints pushed to the unit sphere.
  static const Eigen::Vector3d kAxes[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                           {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  static const int kFaces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                   {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  auto place = [&](const Eigen::Vector3d& unit) {
    return mesh.addVertex(center + unit.normalized().cwiseProduct(radii));
  };
  for (const auto& f : kFaces) {
    const Eigen::Vector3d a = kAxes[f[0]], b = kAxes[f[1]], c = kAxes[f[2]];
    const uint32_t ia = place(a), ib = place(b), ic = place(c);
    const uint32_t ab = place(a + b), bc = place(b + c), ca = place(c + a);
    mesh.addTriangle(ia, ab, ca, style.material, style.label);
    mesh.addTriangle(ab, ib, bc, style.material, style.label);
    mesh.addTriangle(ca, bc, ic, style.material, style.label);
    mesh.addTriangle(ab, bc, ca, style.material, style.label);
  }
}

}  // namespace sim
}  // namespace gmm_localization
