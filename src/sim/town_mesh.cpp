// Ground meshing: per road segment and intersection a grid with 1 m lateral cells (the crown
// profile), per block a grid at sidewalk level, and vertical curb strips between them. All
// grids share their border parameterisation, so neighbouring vertices coincide.
#include "gmm_localization/sim/town_mesh.h"

#include <cmath>

#include "town_blocks.h"

namespace gmm_localization {
namespace sim {
namespace {

class GroundMesher {
 public:
  GroundMesher(const Town& town, const GroundCover& cover, TriangleMesh& mesh)
      : town_(town), cover_(cover), mesh_(mesh), c_(town.config()) {
    lateral_cells_ = 2 * static_cast<int>(std::ceil(0.5 * c_.road_width_m));
  }

  void roads() {
    const auto& xs = town_.roadX();
    const auto& ys = town_.roadY();
    const double h = 0.5 * c_.road_width_m;
    for (size_t i = 0; i < xs.size(); ++i) {
      for (size_t j = 0; j < ys.size(); ++j) {
        // Intersection square: crown over the nearer centreline.
        grid(
            xs[i] - h, xs[i] + h, ys[j] - h, ys[j] + h, lateral_cells_, lateral_cells_,
            [&](double x, double y) {
              return crown(std::min(std::abs(x - xs[i]), std::abs(y - ys[j])));
            },
            [](double, double) { return Material::kAsphalt; });
        if (j + 1 < ys.size()) {  // north-south segment
          const double y0 = ys[j] + h, y1 = ys[j + 1] - h;
          grid(
              xs[i] - h, xs[i] + h, y0, y1, lateral_cells_,
              meshCells(y1 - y0, c_.ground_mesh_step_m),
              [&](double x, double) { return crown(std::abs(x - xs[i])); },
              [](double, double) { return Material::kAsphalt; });
        }
        if (i + 1 < xs.size()) {  // east-west segment
          const double x0 = xs[i] + h, x1 = xs[i + 1] - h;
          grid(
              x0, x1, ys[j] - h, ys[j] + h, meshCells(x1 - x0, c_.ground_mesh_step_m),
              lateral_cells_, [&](double, double y) { return crown(std::abs(y - ys[j])); },
              [](double, double) { return Material::kAsphalt; });
        }
      }
    }
  }

  void blocks() {
    const double s = c_.sidewalk_width_m;
    for (const Block& b : townBlocks(town_)) {
      const int nx = meshCells(b.x1 - b.x0, c_.ground_mesh_step_m);
      const int ny = meshCells(b.y1 - b.y0, c_.ground_mesh_step_m);
      auto material = [&](double x, double y) {
        const bool sidewalk = (b.faces[0] && x < b.x0 + s) || (b.faces[1] && x > b.x1 - s) ||
                              (b.faces[2] && y < b.y0 + s) || (b.faces[3] && y > b.y1 - s);
        return sidewalk ? Material::kConcrete : Material::kGrass;
      };
      grid(
          b.x0, b.x1, b.y0, b.y1, nx, ny, [&](double, double) { return c_.curb_height_m; },
          material);
      if (b.faces[0]) curb(b.x0, b.y0, b.x0, b.y1, ny);
      if (b.faces[1]) curb(b.x1, b.y0, b.x1, b.y1, ny);
      if (b.faces[2]) curb(b.x0, b.y0, b.x1, b.y0, nx);
      if (b.faces[3]) curb(b.x0, b.y1, b.x1, b.y1, nx);
    }
  }

 private:
  double crown(double d) const {
    const double u = 2.0 * d / c_.road_width_m;
    return c_.crown_height_m * (1.0 - u * u);
  }
  double coverAt(double x, double y) const { return cover_.depth_m ? cover_.depth_m(x, y) : 0.0; }
  Material covered(Material m) const { return cover_.depth_m ? cover_.material : m; }

  // Grid whose vertex height is terrain + rel(x, y) + cover, material by cell centre.
  template <typename Rel, typename Mat>
  void grid(double x0, double x1, double y0, double y1, int nx, int ny, Rel rel, Mat mat) {
    const uint32_t first = static_cast<uint32_t>(mesh_.numVertices());
    for (int j = 0; j <= ny; ++j) {
      const double y = y0 + (y1 - y0) * j / ny;
      for (int i = 0; i <= nx; ++i) {
        const double x = x0 + (x1 - x0) * i / nx;
        mesh_.addVertex({x, y, town_.terrainHeight(x, y) + rel(x, y) + coverAt(x, y)});
      }
    }
    const uint32_t row = static_cast<uint32_t>(nx + 1);
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const Material m =
            covered(mat(x0 + (x1 - x0) * (i + 0.5) / nx, y0 + (y1 - y0) * (j + 0.5) / ny));
        const uint32_t a = first + j * row + i;
        mesh_.addTriangle(a, a + 1, a + row + 1, m, kLabelStatic);
        mesh_.addTriangle(a, a + row + 1, a + row, m, kLabelStatic);
      }
    }
  }

  // Vertical curb face along a block edge, from the gutter up to sidewalk level.
  void curb(double x0, double y0, double x1, double y1, int n) {
    const uint32_t first = static_cast<uint32_t>(mesh_.numVertices());
    for (int k = 0; k <= n; ++k) {
      const double x = x0 + (x1 - x0) * k / n, y = y0 + (y1 - y0) * k / n;
      const double t = town_.terrainHeight(x, y) + coverAt(x, y);
      mesh_.addVertex({x, y, t});
      mesh_.addVertex({x, y, t + c_.curb_height_m});
    }
    const Material m = covered(Material::kConcrete);
    for (int k = 0; k < n; ++k) {
      const uint32_t a = first + 2 * k;
      mesh_.addTriangle(a, a + 2, a + 3, m, kLabelStatic);
      mesh_.addTriangle(a, a + 3, a + 1, m, kLabelStatic);
    }
  }

  const Town& town_;
  const GroundCover& cover_;
  TriangleMesh& mesh_;
  const TownConfig& c_;
  int lateral_cells_ = 16;
};

}  // namespace

TriangleMesh buildGroundMesh(const Town& town, const GroundCover& cover) {
  TriangleMesh mesh;
  GroundMesher mesher(town, cover, mesh);
  mesher.roads();
  mesher.blocks();
  return mesh;
}

}  // namespace sim
}  // namespace gmm_localization
