#pragma once
// Map grid geometry: cells, tiles and their indices (the 2D grid of paper section III).
//
// Frames and units: the grid lives in the map frame (REP-105, x east, y north, z up), metres.
// Cell (i, j) covers x in [origin_x_m + i*res, origin_x_m + (i+1)*res) and likewise in y.
// Tile (tx, ty) holds the cells with i in [tx*S, (tx+1)*S), j in [ty*S, (ty+1)*S), S =
// tile_size_cells. Indices may be negative; division is floor division.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include <Eigen/Core>

namespace gmm_localization {

/// Global integer index of one map cell.
struct CellIndex {
  int64_t x = 0;
  int64_t y = 0;
  bool operator==(const CellIndex& o) const { return x == o.x && y == o.y; }
  bool operator!=(const CellIndex& o) const { return !(*this == o); }
};

/// Index of one square tile of cells.
struct TileId {
  int32_t x = 0;
  int32_t y = 0;
  bool operator==(const TileId& o) const { return x == o.x && y == o.y; }
  bool operator!=(const TileId& o) const { return !(*this == o); }
  bool operator<(const TileId& o) const { return x < o.x || (x == o.x && y < o.y); }
};

struct TileIdHash {
  std::size_t operator()(const TileId& t) const {
    return std::hash<uint64_t>()((static_cast<uint64_t>(static_cast<uint32_t>(t.x)) << 32) |
                                 static_cast<uint32_t>(t.y));
  }
};

/// floor(v) as an integer, without a libm call (std::floor is one on baseline x86-64, and the
/// hot loops call it per point). Caller guarantees finite v within the int64 range.
inline int64_t floorToInt(double v) {
  const int64_t i = static_cast<int64_t>(v);  // truncates towards zero
  return i - (static_cast<double>(i) > v ? 1 : 0);
}

/// Floor division for possibly negative integers (b > 0).
inline int64_t floorDiv(int64_t a, int64_t b) {
  const int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

struct MapGeometry {
  static constexpr double kDefaultResolutionM = 0.2;  // the paper's 20 cm cells
  static constexpr int32_t kDefaultTileSizeCells = 320;

  double resolution_m = kDefaultResolutionM;        ///< cell edge [m]
  int32_t tile_size_cells = kDefaultTileSizeCells;  ///< cells per tile edge
  double origin_x_m = 0.0;  ///< map-frame x of the lower-left corner of cell (0, 0) [m]
  double origin_y_m = 0.0;  ///< map-frame y of the lower-left corner of cell (0, 0) [m]

  /// Empty when valid, else which field is wrong and why.
  std::string validate() const {
    if (!(resolution_m > 0.0 && resolution_m <= 10.0 && std::isfinite(resolution_m))) {
      return "resolution_m=" + std::to_string(resolution_m) + " must be in (0, 10]";
    }
    if (tile_size_cells < 8 || tile_size_cells > 4096) {
      return "tile_size_cells=" + std::to_string(tile_size_cells) + " must be in [8, 4096]";
    }
    if (!std::isfinite(origin_x_m) || !std::isfinite(origin_y_m)) return "origin is not finite";
    return {};
  }

  double tileSizeM() const { return resolution_m * tile_size_cells; }

  /// Cell containing map-frame point (x, y) [m]. Caller guarantees finite input.
  CellIndex cellAt(double x, double y) const {
    return {floorToInt((x - origin_x_m) / resolution_m),
            floorToInt((y - origin_y_m) / resolution_m)};
  }
  /// Map-frame centre of a cell [m].
  Eigen::Vector2d cellCenter(const CellIndex& c) const {
    return {origin_x_m + (static_cast<double>(c.x) + 0.5) * resolution_m,
            origin_y_m + (static_cast<double>(c.y) + 0.5) * resolution_m};
  }
  TileId tileOf(const CellIndex& c) const {
    return {static_cast<int32_t>(floorDiv(c.x, tile_size_cells)),
            static_cast<int32_t>(floorDiv(c.y, tile_size_cells))};
  }
  /// First (lowest-index) cell of a tile.
  CellIndex tileOrigin(const TileId& t) const {
    return {static_cast<int64_t>(t.x) * tile_size_cells,
            static_cast<int64_t>(t.y) * tile_size_cells};
  }
  TileId tileAt(double x, double y) const { return tileOf(cellAt(x, y)); }
};

}  // namespace gmm_localization
