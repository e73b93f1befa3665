// Town::generate: street grid, then per block the frontage rows of buildings (setbacks,
// stepped towers, wings, storefront glass, overhangs, awnings), street furniture along the
// sidewalks (trees, lights, signs, hydrants), parking slots and walkways.
#include <algorithm>
#include <cmath>

#include "gmm_localization/sim/random.h"
#include "gmm_localization/sim/town.h"
#include "town_blocks.h"

namespace gmm_localization {
namespace sim {

using Eigen::Vector2d;
using Eigen::Vector3d;

/// Rectangle with a facing side (0 W, 1 E, 2 S, 3 N): the side that fronts a street.
struct Frontage {
  double x0, x1, y0, y1;
  int facing;
};

class TownBuilder {
 public:
  TownBuilder(Town& town, uint64_t seed) : town_(town), rng_(seed) {}

  void build() {
    const TownConfig& c = town_.config_;
    town_.road_x_ = roadLines(c.size_x_m);
    town_.road_y_ = roadLines(c.size_y_m);
    town_.phase_x_ = rng_.uniform(0.0, 2.0 * M_PI);
    town_.phase_y_ = rng_.uniform(0.0, 2.0 * M_PI);
    for (const Block& b : townBlocks(town_)) {
      Rng block_rng = rng_.fork(static_cast<uint64_t>(std::llround(b.x0 * 7.0 + b.y0 * 131.0)));
      addBuildings(b, block_rng);
      addStreetFurniture(b, block_rng);
    }
    addParking();
  }

 private:
  std::vector<double> roadLines(double size) {
    const TownConfig& c = town_.config_;
    const int n =
        std::max(1, static_cast<int>(std::lround(size / (0.5 * (c.block_min_m + c.block_max_m)))));
    std::vector<double> gaps(n);
    double sum = 0.0;
    for (double& g : gaps) sum += (g = rng_.uniform(c.block_min_m, c.block_max_m));
    std::vector<double> lines{0.0};
    double acc = 0.0;
    for (double g : gaps) lines.push_back(acc += g * size / sum);
    lines.back() = size;
    return lines;
  }

  double ground(double x, double y) const {
    return town_.terrainHeight(x, y) + town_.config_.curb_height_m;
  }

  // ---- buildings -------------------------------------------------------------------------
  void addBuildings(const Block& b, Rng& rng) {
    const double s = town_.config_.sidewalk_width_m;
    const double ix0 = b.x0 + (b.faces[0] ? s : 0.0), ix1 = b.x1 - (b.faces[1] ? s : 0.0);
    const double iy0 = b.y0 + (b.faces[2] ? s : 0.0), iy1 = b.y1 - (b.faces[3] ? s : 0.0);
    const double dx = ix1 - ix0, dy = iy1 - iy0;
    if (dx < 12.0 || dy < 12.0) return;
    double d_s = b.faces[2] ? std::min(0.5 * dy, rng.uniform(18.0, 34.0)) : 0.0;
    double d_n = b.faces[3] ? std::min(0.5 * dy, rng.uniform(18.0, 34.0)) : 0.0;
    std::vector<Frontage> rows;
    if (d_s > 0.0) rows.push_back({ix0, ix1, iy0, iy0 + d_s, 2});
    if (d_n > 0.0) rows.push_back({ix0, ix1, iy1 - d_n, iy1, 3});
    const double my0 = iy0 + d_s, my1 = iy1 - d_n;
    if (my1 - my0 >= 12.0) {
      const double d_w = b.faces[0] ? std::min(0.5 * dx, rng.uniform(18.0, 34.0)) : 0.0;
      const double d_e = b.faces[1] ? std::min(0.5 * dx, rng.uniform(18.0, 34.0)) : 0.0;
      if (d_w > 0.0) rows.push_back({ix0, ix0 + d_w, my0, my1, 0});
      if (d_e > 0.0) rows.push_back({ix1 - d_e, ix1, my0, my1, 1});
    }
    for (const Frontage& row : rows) addRow(row, rng);
  }

  // Local frame of a frontage: u along the street, v from the facade line into the block.
  static void toWorld(const Frontage& f, double u0, double u1, double v0, double v1, double* x0,
                      double* x1, double* y0, double* y1) {
    switch (f.facing) {
      case 2:
        *x0 = f.x0 + u0;
        *x1 = f.x0 + u1;
        *y0 = f.y0 + v0;
        *y1 = f.y0 + v1;
        break;
      case 3:
        *x0 = f.x0 + u0;
        *x1 = f.x0 + u1;
        *y0 = f.y1 - v1;
        *y1 = f.y1 - v0;
        break;
      case 0:
        *y0 = f.y0 + u0;
        *y1 = f.y0 + u1;
        *x0 = f.x0 + v0;
        *x1 = f.x0 + v1;
        break;
      default:
        *y0 = f.y0 + u0;
        *y1 = f.y0 + u1;
        *x0 = f.x1 - v1;
        *x1 = f.x1 - v0;
        break;
    }
  }

  void addRow(const Frontage& f, Rng& rng) {
    const bool along_x = f.facing >= 2;
    const double length = along_x ? f.x1 - f.x0 : f.y1 - f.y0;
    const double depth = along_x ? f.y1 - f.y0 : f.x1 - f.x0;
    double u = 0.0;
    while (length - u > 8.0) {
      double w = rng.uniform(14.0, 36.0);
      if (length - u - w < 10.0) w = length - u;
      if (rng.bernoulli(town_.config_.building_density)) addBuilding(f, u, u + w, depth, rng);
      u += w;
    }
  }

  void addBuilding(const Frontage& f, double u0, double u1, double row_depth, Rng& rng) {
    const TownConfig& c = town_.config_;
    const double gap0 = rng.bernoulli(0.55) ? 0.0 : rng.uniform(1.0, 4.0);
    const double gap1 = rng.bernoulli(0.55) ? 0.0 : rng.uniform(1.0, 4.0);
    const double setback = rng.bernoulli(0.5) ? 0.0 : rng.uniform(0.5, 6.0);
    const double bu0 = u0 + gap0, bu1 = u1 - gap1;
    const double depth = std::min(row_depth - setback - 0.5, rng.uniform(12.0, 34.0));
    if (bu1 - bu0 < 6.0 || depth < 6.0) return;
    const double r = rng.uniform();
    const double height =
        c.building_min_height_m + (c.building_max_height_m - c.building_min_height_m) * r * r;
    const Material facade = rng.bernoulli(0.5) ? Material::kWall : Material::kWallBright;

    double x0, x1, y0, y1;
    toWorld(f, bu0, bu1, setback, setback + depth, &x0, &x1, &y0, &y1);
    const double gz = ground(0.5 * (x0 + x1), 0.5 * (y0 + y1));
    const double base =
        std::min({ground(x0, y0), ground(x0, y1), ground(x1, y0), ground(x1, y1)}) - 0.3;
    const bool stepped = height > 14.0 && rng.bernoulli(0.4);
    const double lower_top = stepped ? gz + height * rng.uniform(0.35, 0.6) : gz + height;
    addRect(x0, x1, y0, y1, base, lower_top, facade);
    if (stepped) {
      const double sb = rng.uniform(2.0, 6.0);
      double ux0, ux1, uy0, uy1;
      toWorld(f, bu0 + 1.0, bu1 - 1.0, setback + sb, setback + depth - 1.0, &ux0, &ux1, &uy0, &uy1);
      if (ux1 - ux0 > 4.0 && uy1 - uy0 > 4.0)
        addRect(ux0, ux1, uy0, uy1, lower_top - 0.1, gz + height, facade);
    }
    if (rng.bernoulli(0.25) && row_depth - setback - depth > 6.0) {  // wing behind one end
      const double ww = 0.4 * (bu1 - bu0);
      const double wd = std::min(row_depth - setback - 0.5, depth + rng.uniform(5.0, 15.0));
      const double wu0 = rng.bernoulli(0.5) ? bu0 : bu1 - ww;
      double wx0, wx1, wy0, wy1;
      toWorld(f, wu0, wu0 + ww, setback + depth - 0.2, setback + wd, &wx0, &wx1, &wy0, &wy1);
      addRect(wx0, wx1, wy0, wy1, base, gz + height * rng.uniform(0.5, 1.0), facade);
    }
    addFacadeDetails(f, bu0, bu1, setback, gz, rng);
  }

  // Storefront glass, an overhang slab (with columns when deep) or an awning.
  void addFacadeDetails(const Frontage& f, double u0, double u1, double setback, double gz,
                        Rng& rng) {
    const double reach_max = setback + town_.config_.sidewalk_width_m - 0.6;
    if (rng.bernoulli(0.5)) {
      const double w = u1 - u0;
      addFacadeQuad(f, u0 + 0.1 * w, u1 - 0.1 * w, setback - 0.03, setback - 0.03, gz + 0.3,
                    gz + 3.2, Material::kGlass);
    }
    if (rng.bernoulli(0.22) && reach_max > 1.5) {
      const double reach = std::min(reach_max, rng.uniform(1.5, 3.0));
      const double z0 = gz + rng.uniform(3.2, 4.5);
      double x0, x1, y0, y1;
      toWorld(f, u0 + 0.5, u1 - 0.5, setback - reach, setback, &x0, &x1, &y0, &y1);
      addRect(x0, x1, y0, y1, z0, z0 + 0.3, Material::kRoofing);
      if (reach > 2.2) {
        for (double u = u0 + 1.0; u <= u1 - 0.9; u += std::max(4.0, 0.5 * (u1 - u0 - 2.0))) {
          toWorld(f, u, u + 0.1, setback - reach + 0.3, setback - reach + 0.4, &x0, &x1, &y0, &y1);
          addPrism(town_.objects_, Vector3d(x0, y0, gz - 0.1), 0.2, z0 - gz + 0.1, 8,
                   {Material::kConcrete, kLabelStatic});
        }
      }
    } else if (rng.bernoulli(0.35) && reach_max > 1.0) {
      const double w = std::min(u1 - u0 - 1.0, rng.uniform(3.0, 8.0));
      const double a = rng.uniform(u0 + 0.5, u1 - 0.5 - w);
      const double reach = std::min(reach_max, 1.6);
      addFacadeQuad(f, a, a + w, setback, setback - reach, gz + 3.0, gz + 2.5, Material::kFabric);
    }
  }

  // Quad spanning u in [u0, u1]; its near edge at depth v0 and height z0, far edge at v1, z1.
  void addFacadeQuad(const Frontage& f, double u0, double u1, double v0, double v1, double z0,
                     double z1, Material m) {
    auto point = [&](double u, double v, double z) {
      double x0, x1, y0, y1;
      toWorld(f, u, u, v, v, &x0, &x1, &y0, &y1);
      return Vector3d(x0, y0, z);
    };
    if (v0 == v1) {  // vertical panel
      addQuad(town_.objects_, point(u0, v0, z0), point(u1, v0, z0), point(u1, v0, z1),
              point(u0, v0, z1), {m, kLabelStatic});
    } else {
      addQuad(town_.objects_, point(u0, v0, z0), point(u1, v0, z0), point(u1, v1, z1),
              point(u0, v1, z1), {m, kLabelStatic});
    }
  }

  void addRect(double x0, double x1, double y0, double y1, double z0, double z1, Material m) {
    addBox(town_.objects_, Vector3d(0.5 * (x0 + x1), 0.5 * (y0 + y1), z0),
           Vector3d(x1 - x0, y1 - y0, z1 - z0), 0.0, {m, kLabelStatic});
  }

  // ---- street furniture ------------------------------------------------------------------
  void addStreetFurniture(const Block& b, Rng& rng) {
    const TownConfig& c = town_.config_;
    const double s = c.sidewalk_width_m;
    for (int side = 0; side < 4; ++side) {
      if (!b.faces[side]) continue;
      // Curb line from p0 to p1; `in` points from the curb into the sidewalk.
      Vector2d p0, p1, in;
      switch (side) {
        case 0:
          p0 = {b.x0, b.y0};
          p1 = {b.x0, b.y1};
          in = {1, 0};
          break;
        case 1:
          p0 = {b.x1, b.y0};
          p1 = {b.x1, b.y1};
          in = {-1, 0};
          break;
        case 2:
          p0 = {b.x0, b.y0};
          p1 = {b.x1, b.y0};
          in = {0, 1};
          break;
        default:
          p0 = {b.x0, b.y1};
          p1 = {b.x1, b.y1};
          in = {0, -1};
          break;
      }
      const double len = (p1 - p0).norm();
      const Vector2d dir = (p1 - p0) / len;
      town_.walkways_.push_back(
          {p0 + dir * (0.5 * s) + in * (0.5 * s), p1 - dir * (0.5 * s) + in * (0.5 * s)});
      std::vector<double> taken;
      if (c.tree_spacing_m > 0.0) {
        for (double u = 9.0 + rng.uniform(0.0, c.tree_spacing_m); u < len - 9.0;
             u += c.tree_spacing_m) {
          const double uu = u + rng.uniform(-1.5, 1.5);
          if (!rng.bernoulli(c.tree_probability)) continue;
          addTree(p0 + dir * uu + in * 1.0, rng);
          taken.push_back(uu);
        }
      }
      if (c.pole_spacing_m > 0.0) {
        for (double u = 6.0 + rng.uniform(0.0, c.pole_spacing_m); u < len - 6.0;
             u += c.pole_spacing_m) {
          double uu = u;
          for (double t : taken)
            if (std::abs(t - uu) < 2.5) uu = t + 3.0;
          if (uu > len - 3.0) continue;
          addStreetLight(p0 + dir * uu + in * 0.5, -in);
        }
      }
      if (rng.bernoulli(0.5)) addSign(p0 + dir * 2.0 + in * 0.6, dir, Vector3d(0.65, 0.04, 0.65));
      for (double u = 20.0; u < len - 20.0; u += 40.0) {
        if (rng.bernoulli(0.3))
          addSign(p0 + dir * (u + rng.uniform(-3, 3)) + in * 0.4, dir, Vector3d(0.3, 0.03, 0.45));
      }
      if (rng.bernoulli(0.4)) {
        const Vector2d h = p0 + dir * rng.uniform(5.0, std::max(6.0, len - 5.0)) + in * 0.6;
        addPrism(town_.objects_, Vector3d(h.x(), h.y(), ground(h.x(), h.y()) - 0.05), 0.15, 0.75, 6,
                 {Material::kMetal, kLabelStatic});
      }
    }
  }

  void addTree(const Vector2d& p, Rng& rng) {
    const double gz = ground(p.x(), p.y());
    const double trunk_h = rng.uniform(2.0, 3.5);
    addPrism(town_.objects_, Vector3d(p.x(), p.y(), gz - 0.1), rng.uniform(0.12, 0.25),
             trunk_h + 0.6, 6, {Material::kBark, kLabelStatic});
    const double rh = rng.uniform(1.8, 3.5), rv = rng.uniform(1.5, 3.0);
    const Vector3d center(p.x(), p.y(), gz + trunk_h + 0.8 * rv);
    town_.trees_.push_back({center, rh, rv});  // recorded only: no draw, mesh unchanged
    const int blobs = 5 + rng.uniformInt(3);
    for (int k = 0; k < blobs; ++k) {
      const Vector3d off(rng.uniform(-0.5, 0.5) * rh, rng.uniform(-0.5, 0.5) * rh,
                         rng.uniform(-0.4, 0.4) * rv);
      const double f = rng.uniform(0.45, 0.65);
      addEllipsoid(town_.objects_, center + off, Vector3d(f * rh, f * rh, f * rv),
                   {Material::kFoliage, kLabelStatic});
    }
  }

  void addStreetLight(const Vector2d& p, const Vector2d& toward_road) {
    const double gz = ground(p.x(), p.y());
    const MeshStyle metal{Material::kMetal, kLabelStatic};
    addPrism(town_.objects_, Vector3d(p.x(), p.y(), gz - 0.1), 0.1, 7.6, 8, metal);
    const double yaw = std::atan2(toward_road.y(), toward_road.x());
    const Vector2d arm = p + toward_road * 0.9;
    addBox(town_.objects_, Vector3d(arm.x(), arm.y(), gz + 7.3), Vector3d(1.8, 0.12, 0.12), yaw,
           metal);
    const Vector2d lamp = p + toward_road * 1.8;
    addBox(town_.objects_, Vector3d(lamp.x(), lamp.y(), gz + 7.15), Vector3d(0.6, 0.3, 0.15), yaw,
           metal);
  }

  void addSign(const Vector2d& p, const Vector2d& along, const Vector3d& plate) {
    const double gz = ground(p.x(), p.y());
    addPrism(town_.objects_, Vector3d(p.x(), p.y(), gz - 0.1), 0.04, 2.2 + plate.z(), 6,
             {Material::kMetal, kLabelStatic});
    const double yaw = std::atan2(along.y(), along.x()) + 0.5 * M_PI;
    const Vector2d q = p - along * 0.06;
    addBox(town_.objects_, Vector3d(q.x(), q.y(), gz + 2.2),
           Vector3d(plate.y(), plate.x(), plate.z()), yaw, {Material::kSign, kLabelStatic});
  }

  // ---- parking ---------------------------------------------------------------------------
  void addParking() {
    const TownConfig& c = town_.config_;
    if (c.parking_lane_m < 1.8) return;
    const double half = 0.5 * c.road_width_m;
    const double off = town_.laneOffsets().parking_m;
    auto slots = [&](double a, double b, auto place) {
      const double lo = a + half + 8.0, hi = b - half - 8.0;
      const int n = static_cast<int>(std::floor((hi - lo) / c.parking_slot_m));
      for (int k = 0; k < n; ++k) place(lo + (k + 0.5) * (hi - lo) / n);
    };
    const auto& xs = town_.road_x_;
    const auto& ys = town_.road_y_;
    for (double x : xs) {
      for (size_t j = 0; j + 1 < ys.size(); ++j) {
        slots(ys[j], ys[j + 1], [&](double y) {
          town_.parking_.push_back({{x + off, y}, 0.5 * M_PI});
          town_.parking_.push_back({{x - off, y}, -0.5 * M_PI});
        });
      }
    }
    for (double y : ys) {
      for (size_t i = 0; i + 1 < xs.size(); ++i) {
        slots(xs[i], xs[i + 1], [&](double x) {
          town_.parking_.push_back({{x, y - off}, 0.0});
          town_.parking_.push_back({{x, y + off}, M_PI});
        });
      }
    }
  }

  Town& town_;
  Rng rng_;
};

Result<Town> Town::generate(const TownConfig& config) {
  const Status valid = config.validate();
  if (!valid) return Result<Town>::failure(valid.error());
  Town town;
  town.config_ = config;
  TownBuilder(town, config.seed).build();
  return town;
}

}  // namespace sim
}  // namespace gmm_localization
