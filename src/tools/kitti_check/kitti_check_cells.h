#pragma once
// What the Gaussian mixtures look like on real ground, walls and vegetation: each map
// cell with data is given a class from the points it was built from, by the local shape of
// those points (eigenvalues of their covariance within a ball, Demantke et al. 2011's
// dimensionality features), and the mixtures are summarised per class.
//
// Point classes:
//  - ground: within ground_band_m above (and below_ground_m below) the ground level of its
//    ground_cell_m square: the lowest height with at least 5 of the square's points within
//    ground_band_m above it (so isolated returns below the road do not count), replaced by a
//    robust plane through all squares' levels where it is more than 0.5 m off that plane (a
//    square with no ground return, e.g. under a canopy, or one whose lowest returns are ghosts).
//    A plane suits a street a hundred metres long; hilly maps would need a smoother surface;
//  - below ground: more than below_ground_m under the level: on KITTI, vertical streaks of
//    returns mirrored by car windows and shop fronts (multipath ghosts);
//  - above the band, from the points within neighbour_radius_m: wall = planar (the
//    dimensionality a2 = (s2 - s3) / s1 dominates, s_i = sqrt of the eigenvalues, descending)
//    with a horizontal normal (|n_z| <= wall_max_normal_z); vegetation = scattered (a3 = s3 / s1
//    dominates); other = linear (poles, trunks, edges), horizontal planes (car roofs, awnings)
//    and points with fewer than min_neighbours neighbours.
// Cell classes: ground when every point of the column is ground, else the most common class of
// its above-ground points.

#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "gmm_localization/core/map/gmm_tile.h"
#include "gmm_localization/core/matching/scan_filter.h"

namespace gmm_localization {
namespace kitti_check {

enum class PointClass { kGround = 0, kWall = 1, kVegetation = 2, kOther = 3, kBelowGround = 4 };
constexpr int kPointClasses = 5;
const char* className(PointClass c);

struct ClassifierOptions {
  double ground_cell_m = 2.0;        ///< square for the ground level [m]
  double ground_band_m = 0.3;        ///< ground: within this of the ground level [m]
  double neighbour_radius_m = 0.75;  ///< ball for the shape features [m]
  int min_neighbours = 8;            ///< fewer: class other
  double wall_max_normal_z = 0.3;    ///< |n_z| of a wall's normal at most this
  double below_ground_m = 0.5;       ///< below ground: lower than the level by more [m]
};

struct PointLabels {
  std::vector<PointClass> labels;  ///< one per point
  std::vector<float> ground_z;     ///< ground level under each point [m]
};

/// Labels map-frame points (z up). Deterministic.
PointLabels classifyPoints(const PointList& points, const ClassifierOptions& options);

/// A map cell with data, its class and the points of its own column.
struct CellRecord {
  CellIndex cell;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< map frame [m]
  PointClass cls = PointClass::kOther;
  GaussianMixture1D mixture;
  float ground_z = 0.f;  ///< ground level under the cell [m]
  std::array<int, kPointClasses> points_by_class{};
  std::vector<float> z;            ///< heights of the column's points [m], ascending
  std::vector<float> neighbour_z;  ///< heights in the 8 neighbouring columns (the blur's reach)
  int points() const;
};

/// Every cell of `map` with data and at least one input point in its column (a cell can hold a
/// mixture from the blur alone when min_own_points is 0; those are skipped).
std::vector<CellRecord> classifyCells(const GmmMap& map, const PointList& points,
                                      const PointLabels& labels);

/// Per-class summary of the mixtures (markdown), for all cells and for well-observed ones, then
/// the example cells (see exampleCells) with their mixtures and column heights.
void printCellTables(const std::vector<CellRecord>& cells, const std::vector<size_t>& examples,
                     std::FILE* out);

/// Example cells: for each class and K, among the cells within radius_m of a centre (all when
/// there is no centre) in the top decile of points, the one whose sigma (K = 1) or distance
/// between the means (K = 2) is nearest the median of the class and K.
std::vector<size_t> exampleCells(const std::vector<CellRecord>& cells,
                                 const std::vector<Eigen::Vector2d>& centres = {},
                                 double radius_m = 0.0);

/// cells.csv: x_m,y_m,class,k,w0,mu0,sigma0,w1,mu1,sigma1,w2,mu2,sigma2,ground_z,points.
/// examples.csv: the same columns plus z and neighbour_z (heights, ';'-separated).
bool writeCellsCsv(const std::vector<CellRecord>& cells, const std::vector<size_t>& examples,
                   const std::string& cells_path, const std::string& examples_path);

}  // namespace kitti_check
}  // namespace gmm_localization
