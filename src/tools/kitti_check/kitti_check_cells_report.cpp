// Tables and CSV files of the per-class summary of the mixtures (kitti_check_cells.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "bench/bench_data.h"
#include "kitti_check/kitti_check_cells.h"

namespace gmm_localization {
namespace kitti_check {

namespace {
using bench::median;
using bench::percentile;
double quantile(std::vector<double> v, double p) { return percentile(std::move(v), p); }
}  // namespace

namespace {
/// A number with `digits` decimals, "-" for NaN (no cell to take a median of).
std::string num(double v, int digits) {
  if (!std::isfinite(v)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

void printClassTable(const std::vector<CellRecord>& cells, int min_points, std::FILE* out) {
  std::fprintf(out,
               "| cell class | cells | share of cells with data | K=1 / K=2 | K=1: sigma median "
               "(p10-p90) m | K=1: mean - ground median m | K=2: lower / upper sigma median m | "
               "K=2: lower weight median | K=2: gap between means median m | column points "
               "median | column height span median m |\n|---|---|---|---|---|---|---|---|---|---|"
               "---|\n");
  size_t total = 0;
  for (const CellRecord& r : cells) total += r.points() >= min_points;
  for (int c = 0; c < kPointClasses; ++c) {
    std::vector<double> s1, d1, lo, hi, wlo, gap, npts, span;
    int n = 0, k1 = 0, k2 = 0;
    for (const CellRecord& r : cells) {
      if (static_cast<int>(r.cls) != c || r.points() < min_points) continue;
      ++n;
      npts.push_back(r.points());
      span.push_back(r.z.back() - r.z.front());
      const GaussianMixture1D& g = r.mixture;
      if (g.size() == 1) {
        ++k1;
        s1.push_back(g.component(0).sigma_m);
        d1.push_back(g.component(0).mean_m - r.ground_z);
      } else if (g.size() >= 2) {
        ++k2;
        const int a = g.component(0).mean_m <= g.component(1).mean_m ? 0 : 1;
        lo.push_back(g.component(a).sigma_m);
        hi.push_back(g.component(1 - a).sigma_m);
        wlo.push_back(g.component(a).weight);
        gap.push_back(g.component(1 - a).mean_m - g.component(a).mean_m);
      }
    }
    const std::string sigma1 = s1.empty() ? "-"
                                          : num(median(s1), 3) + " (" + num(quantile(s1, 10), 3) +
                                                "-" + num(quantile(s1, 90), 3) + ")";
    std::fprintf(out,
                 "| %s | %d | %.1f%% | %.0f%% / %.0f%% | %s | %s | %s / %s | %s | %s | %s | %s |\n",
                 className(static_cast<PointClass>(c)), n, 100.0 * n / std::max<size_t>(1, total),
                 100.0 * k1 / std::max(1, n), 100.0 * k2 / std::max(1, n), sigma1.c_str(),
                 num(median(d1), 2).c_str(), num(median(lo), 2).c_str(), num(median(hi), 2).c_str(),
                 num(median(wlo), 2).c_str(), num(median(gap), 2).c_str(),
                 num(median(npts), 0).c_str(), num(median(span), 2).c_str());
  }
}
}  // namespace

void printCellTables(const std::vector<CellRecord>& cells, const std::vector<size_t>& examples,
                     std::FILE* out) {
  std::fprintf(out, "All cells with data:\n\n");
  printClassTable(cells, 1, out);
  constexpr int kWellObserved = 5;
  std::fprintf(out, "\nWell-observed cells only (at least %d points in the cell's own column):\n\n",
               kWellObserved);
  printClassTable(cells, kWellObserved, out);
  std::fprintf(
      out,
      "\nExample cells (for each class and K, near the keyframes, among the cells with the "
      "most points (top decile), the one whose sigma (K=1) or distance between means "
      "(K=2) is nearest the median):\n\n");
  std::fprintf(
      out,
      "| class | cell centre x, y m | ground m | column points (ground/wall/veg/other/below) | "
      "column z min / median / max m | mixture (w, mean m, sigma m) |\n"
      "|---|---|---|---|---|---|\n");
  for (size_t i : examples) {
    const CellRecord& r = cells[i];
    std::string mix;
    for (int j = 0; j < r.mixture.size(); ++j) {
      const GaussianComponent& g = r.mixture.component(j);
      char buf[96];
      std::snprintf(buf, sizeof(buf), "%s(%.2f, %.2f, %.3f)", j ? " + " : "", g.weight, g.mean_m,
                    g.sigma_m);
      mix += buf;
    }
    std::fprintf(
        out, "| %s | %.1f, %.1f | %.2f | %d (%d/%d/%d/%d/%d) | %.2f / %.2f / %.2f | %s |\n",
        className(r.cls), r.centre.x(), r.centre.y(), r.ground_z, r.points(), r.points_by_class[0],
        r.points_by_class[1], r.points_by_class[2], r.points_by_class[3], r.points_by_class[4],
        r.z.front(), r.z[r.z.size() / 2], r.z.back(), mix.c_str());
  }
}

namespace {
void writeRow(std::FILE* f, const CellRecord& r) {
  std::fprintf(f, "%.3f,%.3f,%s,%d", r.centre.x(), r.centre.y(), className(r.cls),
               r.mixture.size());
  for (int j = 0; j < kMaxMixtureComponents; ++j) {
    if (j < r.mixture.size()) {
      const GaussianComponent& g = r.mixture.component(j);
      std::fprintf(f, ",%.4f,%.4f,%.4f", g.weight, g.mean_m, g.sigma_m);
    } else {
      std::fprintf(f, ",,,");
    }
  }
  std::fprintf(f, ",%.3f,%d", r.ground_z, r.points());
}
}  // namespace

bool writeCellsCsv(const std::vector<CellRecord>& cells, const std::vector<size_t>& examples,
                   const std::string& cells_path, const std::string& examples_path) {
  const char* header = "x_m,y_m,class,k,w0,mu0,sigma0,w1,mu1,sigma1,w2,mu2,sigma2,ground_z,points";
  std::FILE* f = std::fopen(cells_path.c_str(), "w");
  if (f == nullptr) return false;
  std::fprintf(f, "%s\n", header);
  for (const CellRecord& r : cells) {
    writeRow(f, r);
    std::fprintf(f, "\n");
  }
  if (std::fclose(f) != 0) return false;
  f = std::fopen(examples_path.c_str(), "w");
  if (f == nullptr) return false;
  std::fprintf(f, "%s,z,neighbour_z\n", header);
  for (size_t i : examples) {
    writeRow(f, cells[i]);
    for (const std::vector<float>* z : {&cells[i].z, &cells[i].neighbour_z}) {
      std::fprintf(f, ",");
      for (size_t j = 0; j < z->size(); ++j) std::fprintf(f, "%s%.3f", j ? ";" : "", (*z)[j]);
    }
    std::fprintf(f, "\n");
  }
  return std::fclose(f) == 0;
}

}  // namespace kitti_check
}  // namespace gmm_localization
