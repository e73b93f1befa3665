// map_info: summary of a Gaussian mixture map, CRC verification of every tile, a top-down
// component-count image (the paper's Fig. 3 view), a CSV of the cells, and single-cell dumps.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

#include "common/cli_args.h"
#include "gmm_localization/core/map/map_store.h"

using namespace gmm_localization;

namespace {

const char* kHelp = R"(map_info: summary, verification and export of a Gaussian mixture map.

Usage: map_info MAP_DIR [options]

Prints the manifest summary (format version, layer, geometry, georeference, provenance,
tiles, cells with 0/1/2/3 components, bytes on disk, extent), then loads every tile and checks
its size, CRC-32 and header. The layer is height (the paper's map) or reflectivity (cells over
the ground returns' intensity x metres per unit instead of height: build_map --layer). Exit code: 0 sound, 3 when any tile is missing or corrupted, 1 when the manifest cannot
be read, 2 on a usage error.

Options:
  --no-verify        skip loading the tiles (summary from the manifest only)
  --ppm FILE         top-down image, one pixel per cell, north up: white = 0 components,
                     blue = 1, purple = 2, red = 3 (the paper's Fig. 3 colours), grey = no tile
  --csv FILE         one row per cell with data: x_m,y_m,k,w0,mu0,sigma0,w1,mu1,sigma1,w2,mu2,sigma2
                     (cell centres, map frame; input of scripts/plot_map_components.py)
  --stride N         export every N-th cell in x and y (1)
  --cell X,Y         print the mixtures of the cell containing map point (X, Y) and of its
                     neighbours within --cell-radius cells (1)
  --help
)";

bool parsePair(const char* text, double& a, double& b) {
  char* end = nullptr;
  a = std::strtod(text, &end);
  if (*end != ',') return false;
  b = std::strtod(end + 1, &end);
  return *end == '\0' && std::isfinite(a) && std::isfinite(b);
}

void printMixture(const GaussianMixture1D& g) {
  if (g.empty()) {
    std::printf("empty");
    return;
  }
  for (int j = 0; j < g.size(); ++j) {
    const auto& c = g.component(j);
    std::printf("%s[w %.3f  mu %+.3f m  sigma %.3f m]", j ? "  " : "", c.weight, c.mean_m,
                c.sigma_m);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string dir, ppm, csv;
  bool verify = true, want_cell = false;
  int stride = 1, cell_radius = 1;
  double cx = 0, cy = 0;
  gmm_localization::tools::NormalizedArgs args(argc, argv);
  argc = args.argc();
  argv = args.argv();
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::cerr << "map_info: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--help" || a == "-h") {
      std::cout << kHelp;
      return 0;
    } else if (a == "--no-verify") {
      verify = false;
    } else if (a == "--ppm") {
      ppm = value();
    } else if (a == "--csv") {
      csv = value();
    } else if (a == "--stride") {
      stride = std::atoi(value());
    } else if (a == "--cell-radius") {
      cell_radius = std::atoi(value());
    } else if (a == "--cell") {
      want_cell = parsePair(value(), cx, cy);
      if (!want_cell) {
        std::cerr << "map_info: --cell needs X,Y\n";
        return 2;
      }
    } else if (!a.empty() && a[0] != '-' && dir.empty()) {
      dir = a;
    } else {
      std::cerr << "map_info: unknown argument '" << a << "' (see --help)\n";
      return 2;
    }
  }
  if (dir.empty() || stride < 1 || cell_radius < 0 || cell_radius > 50) {
    std::cerr
        << "map_info: give a map directory (and --stride >= 1, --cell-radius 0..50); see --help\n";
    return 2;
  }
  auto store = MapStore::open(dir);
  if (!store) {
    std::cerr << "map_info: " << store.error() << "\n";
    return 1;
  }
  const MapManifest& m = store->manifest();
  const MapGeometry& g = m.geometry;
  const MapSummary s = store->summary();
  std::printf("map              %s (format version %u)\n", dir.c_str(), m.format_version);
  const bool reflectivity = m.layer == MapLayer::kReflectivity;
  std::printf("layer            %s", mapLayerName(m.layer));
  if (reflectivity) std::printf(" (%s)", describeReflectivityLayer(m.reflectivity).c_str());
  std::printf("\n");
  std::printf("geometry         %.3f m cells, %d-cell tiles (%.1f m), origin (%.3f, %.3f) m\n",
              g.resolution_m, g.tile_size_cells, g.tileSizeM(), g.origin_x_m, g.origin_y_m);
  std::printf("georeference     %s\n", m.georeference.describe().c_str());
  std::printf("provenance       %s\n", m.provenance.c_str());
  std::printf("tiles            %zu\n", s.tiles);
  // In a reflectivity map the tiles' z ranges are values: also shown as intensities.
  std::printf("extent           x [%.1f, %.1f] m, y [%.1f, %.1f] m, %s [%.2f, %.2f] m", s.min_x_m,
              s.max_x_m, s.min_y_m, s.max_y_m, reflectivity ? "value" : "z", s.z_min_m, s.z_max_m);
  if (reflectivity) {
    std::printf(" = intensity [%.1f, %.1f]", s.z_min_m / m.reflectivity.metres_per_unit,
                s.z_max_m / m.reflectivity.metres_per_unit);
  }
  std::printf(" (mean -/+ 4 sigma)\n");
  const uint64_t non_empty = s.nonEmptyCells();
  std::printf("cells            %llu in tiles, %llu with data (%.3f km^2)\n",
              static_cast<unsigned long long>(s.cells()),
              static_cast<unsigned long long>(non_empty),
              non_empty * g.resolution_m * g.resolution_m / 1e6);
  for (int k = 0; k <= kMaxMixtureComponents; ++k) {
    std::printf("  %d component%s   %12llu", k, k == 1 ? " " : "s",
                static_cast<unsigned long long>(s.cells_by_components[k]));
    if (k > 0 && non_empty)
      std::printf("  (%.1f%% of cells with data)", 100.0 * s.cells_by_components[k] / non_empty);
    std::printf("\n");
  }
  std::printf(
      "on disk          %.3f MB (tiles %.3f MB, manifest %.1f kB), %.2f B per cell with data\n",
      s.bytesOnDisk() / 1e6, s.tile_bytes / 1e6, s.manifest_bytes / 1e3,
      non_empty ? static_cast<double>(s.bytesOnDisk()) / non_empty : 0.0);

  int status = 0;
  if (verify) {
    const auto errors = store->verify();
    for (const auto& e : errors) std::printf("CORRUPT          %s\n", e.c_str());
    std::printf("verify           %zu of %zu tiles sound\n", s.tiles - errors.size(), s.tiles);
    if (!errors.empty()) status = 3;
  }

  if (want_cell) {
    const CellIndex c0 = g.cellAt(cx, cy);
    for (int dy = cell_radius; dy >= -cell_radius; --dy) {
      for (int dx = -cell_radius; dx <= cell_radius; ++dx) {
        const CellIndex c{c0.x + dx, c0.y + dy};
        const Eigen::Vector2d centre = g.cellCenter(c);
        std::printf("cell (%lld, %lld) at (%.2f, %.2f): ", static_cast<long long>(c.x),
                    static_cast<long long>(c.y), centre.x(), centre.y());
        auto tile = store->hasTile(g.tileOf(c)) ? store->loadTile(g.tileOf(c))
                                                : Result<GmmTileConstPtr>::failure("no tile");
        if (!tile) {
          std::printf("%s\n", tile.error().c_str());
          continue;
        }
        const CellIndex o = g.tileOrigin(g.tileOf(c));
        printMixture((*tile)->at(static_cast<int32_t>(c.x - o.x), static_cast<int32_t>(c.y - o.y)));
        std::printf("\n");
      }
    }
  }

  if (!ppm.empty() || !csv.empty()) {
    const int64_t x0 = std::llround((s.min_x_m - g.origin_x_m) / g.resolution_m);
    const int64_t y0 = std::llround((s.min_y_m - g.origin_y_m) / g.resolution_m);
    const int64_t w = std::llround((s.max_x_m - s.min_x_m) / g.resolution_m) / stride;
    const int64_t h = std::llround((s.max_y_m - s.min_y_m) / g.resolution_m) / stride;
    if (w * h > 400000000LL) {
      std::cerr << "map_info: image of " << w << " x " << h
                << " pixels is too large; use --stride\n";
      return 2;
    }
    std::vector<uint8_t> rgb(static_cast<size_t>(w * h) * 3, 200);
    FILE* out = csv.empty() ? nullptr : std::fopen(csv.c_str(), "w");
    if (!csv.empty() && !out) {
      std::cerr << "map_info: cannot write " << csv << "\n";
      return 1;
    }
    if (out) std::fprintf(out, "x_m,y_m,k,w0,mu0,sigma0,w1,mu1,sigma1,w2,mu2,sigma2\n");
    static const uint8_t kColour[4][3] = {
        {255, 255, 255}, {40, 90, 220}, {140, 40, 160}, {220, 30, 30}};
    for (const TileId& id : store->tileIds()) {
      auto tile = store->loadTile(id);
      if (!tile) continue;  // reported by verify
      const CellIndex o = g.tileOrigin(id);
      for (int32_t ly = 0; ly < g.tile_size_cells; ++ly) {
        for (int32_t lx = 0; lx < g.tile_size_cells; ++lx) {
          const int64_t gx = o.x + lx - x0, gy = o.y + ly - y0;
          if (gx % stride || gy % stride) continue;
          const int64_t px = gx / stride, py = h - 1 - gy / stride;
          if (px < 0 || px >= w || py < 0 || py >= h) continue;
          const GaussianMixture1D& mix = (*tile)->at(lx, ly);
          std::memcpy(&rgb[static_cast<size_t>(py * w + px) * 3], kColour[mix.size()], 3);
          if (out && !mix.empty()) {
            const Eigen::Vector2d c = g.cellCenter({o.x + lx, o.y + ly});
            std::fprintf(out, "%.3f,%.3f,%d", c.x(), c.y(), mix.size());
            for (int j = 0; j < kMaxMixtureComponents; ++j) {
              if (j < mix.size()) {
                const auto& q = mix.component(j);
                std::fprintf(out, ",%.4f,%.4f,%.4f", q.weight, q.mean_m, q.sigma_m);
              } else {
                std::fprintf(out, ",,,");
              }
            }
            std::fprintf(out, "\n");
          }
        }
      }
    }
    if (out && std::fclose(out) != 0) {
      std::cerr << "map_info: write error on " << csv << "\n";
      return 1;
    }
    if (!ppm.empty()) {
      std::ofstream f(ppm, std::ios::binary);
      f << "P6\n" << w << " " << h << "\n255\n";
      f.write(reinterpret_cast<const char*>(rgb.data()), static_cast<std::streamsize>(rgb.size()));
      if (!f) {
        std::cerr << "map_info: cannot write " << ppm << "\n";
        return 1;
      }
      std::printf("image            %s (%lld x %lld px, %g m per px)\n", ppm.c_str(),
                  static_cast<long long>(w), static_cast<long long>(h), g.resolution_m * stride);
    }
    if (!csv.empty()) std::printf("csv              %s\n", csv.c_str());
  }
  return status;
}
