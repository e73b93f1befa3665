#pragma once
// The discretised x, y, heading search space of paper III-A / Algorithm 2, shared by the
// exhaustive search, the branch-and-bound search and the covariance estimate.
//
// Translations: x = prior.x + (tx - half_x) * res, y = prior.y + (ty - half_y) * res with
// tx in [0, 2 half_x], ty in [0, 2 half_y]; headings: yaw = prior.yaw + (j - half_h) * step,
// j in [0, 2 half_h]. z, roll and pitch stay at the prior's. The cloud is rotated once per
// heading ("rotate once, then translations are integer cell offsets"): a translation by whole
// cells shifts every point's cell index by the same integers, exactly.
//
// Channels. A problem may carry a second point set scored against a second map over the same
// poses (the fused method: the reflectivity layer's ground returns, MatchRequest::fused in
// registration.h). Each channel has its own raster window and its own per-heading cells, and every
// score below is the sum of the two channels' scores. The sum of two admissible upper bounds is an
// admissible upper bound of the sum (max over a node's leaves of a + b <= max of a + max of b), so
// every search, bound, covariance and certificate built on these scores stays exact and unchanged.
// Both maps must share cells, chunks, layers and score quantization (channelCompatibility): then a
// translation by whole cells shifts both channels' points alike, node blocks cover the same
// cells in both, and the sum of table values is a sum of log-likelihoods in one unit.

#include <cstdint>
#include <string>
#include <vector>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/common/task_pool.h"
#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/matching/scan_filter.h"
#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {

struct SearchWindow {
  Pose6 prior;     ///< window centre
  int half_x = 0;  ///< translations each side in x [cells]
  int half_y = 0;  ///< translations each side in y [cells]
  int half_h = 0;  ///< heading steps each side
  double heading_step_rad = 0.0;

  int sizeX() const { return 2 * half_x + 1; }
  int sizeY() const { return 2 * half_y + 1; }
  int sizeH() const { return 2 * half_h + 1; }
  /// Number of poses the exhaustive search scores.
  int64_t poses() const { return static_cast<int64_t>(sizeX()) * sizeY() * sizeH(); }

  /// Window covering +-half_extent_x/y_m [m] and +-half_heading_rad [rad] around prior.
  static SearchWindow fromExtent(const Pose6& prior, double half_extent_x_m, double half_extent_y_m,
                                 double half_heading_rad, double heading_step_rad,
                                 double resolution_m);
  std::string validate() const;
};

/// A scan point at a given heading, as a cell and z bin for translation (tx, ty) = (0, 0),
/// with the number of scan points merged into it.
struct CellPoint {
  int32_t gx;
  int32_t gy;
  int32_t zb;
  uint32_t count;
};

/// Constant-time raster lookups over the chunks a search can touch: a dense grid of chunk
/// pointers (nullptr where no chunk is loaded: the floor, 0).
class RasterWindow {
 public:
  /// Covers global cells [gx_min, gx_max] x [gy_min, gy_max] of `map`.
  RasterWindow(const ChunkMap& map, int64_t gx_min, int64_t gy_min, int64_t gx_max, int64_t gy_max);

  const MapChunk* chunk(int64_t gx, int64_t gy) const {
    const int64_t cx = (gx >> shift_) - cx0_;
    const int64_t cy = (gy >> shift_) - cy0_;
    if (cx < 0 || cy < 0 || cx >= w_ || cy >= h_) return nullptr;
    return grid_[static_cast<size_t>(cy * w_ + cx)];
  }
  uint8_t value(int layer, int64_t gx, int64_t gy, int32_t zb) const {
    const MapChunk* c = chunk(gx, gy);
    if (c == nullptr) return 0;
    return c->value(layer, zb, static_cast<int>(gx & mask_), static_cast<int>(gy & mask_));
  }
  /// An upper bound of layer `layer`'s block starting at (gx, gy) (a node's bound): the stored
  /// value when that cell's chunk is loaded. When it is not, the block (2^layer cells, at most a
  /// chunk) may still reach into loaded neighbours, whose parts are bounded by the layer's
  /// values at their first cells; parts in chunks that are not loaded read the floor (0) at the
  /// base layer too. Equals value() at layer 0 and wherever the chunk is loaded.
  uint8_t blockBound(int layer, int64_t gx, int64_t gy, int32_t zb) const {
    const MapChunk* c = chunk(gx, gy);
    if (c != nullptr) {
      return c->value(layer, zb, static_cast<int>(gx & mask_), static_cast<int>(gy & mask_));
    }
    return layer == 0 ? 0 : neighbourBound(layer, gx, gy, int64_t{1} << layer, zb);
  }
  /// The parts of block [gx, gx + size) x [gy, gy + size) (size at most a chunk, the chunk of
  /// (gx, gy) not loaded) in the next chunks towards +x and +y, bounded by `layer`'s values at
  /// their first cells (which cover 2^layer >= size cells each).
  uint8_t neighbourBound(int layer, int64_t gx, int64_t gy, int64_t size, int32_t zb) const;
  int shift() const { return shift_; }
  size_t chunksPresent() const;

 private:
  int shift_ = 0;
  int64_t mask_ = 0;
  int64_t cx0_ = 0, cy0_ = 0, w_ = 0, h_ = 0;
  std::vector<const MapChunk*> grid_;
};

/// The second channel of a search (see the top of this file): `points` in the levelled base
/// frame with absolute heights (their z is not raised by the prior's, unlike the first
/// channel's), scored against `map`. Both must outlive SearchProblem::create.
struct SecondChannel {
  const ChunkMap* map = nullptr;
  const PointList* points = nullptr;
};

/// Empty when the two maps can be searched together as channels of one problem (same cell
/// size and origin, chunk size, number of layers and score quantization), else the reason.
std::string channelCompatibility(const ChunkMap& first, const ChunkMap& second);

/// A scan prepared for searching one window: its points rotated and discretised per heading.
class SearchProblem {
 public:
  /// `points` in the levelled base frame (see filterScan). Fails when the window is invalid,
  /// there are no points, or no point of any pose lands on a loaded chunk ("off the map").
  /// `pool`: the headings in parallel (the same problem). `second`: a second channel; fails too
  /// when its map is incompatible (channelCompatibility), it has no points, or none of them
  /// lands on a loaded chunk of its map.
  static Result<SearchProblem> create(const ChunkMap& map, const PointList& points,
                                      const SearchWindow& window, TaskPool* pool = nullptr,
                                      const SecondChannel* second = nullptr);

  const SearchWindow& window() const { return window_; }
  /// The first channel's map (the geometry and quantization both channels share).
  const ChunkMap& map() const { return *map_; }
  int numChannels() const { return static_cast<int>(channels_.size()); }
  const RasterWindow& raster(int channel = 0) const { return channels_[channel].raster; }
  const std::vector<CellPoint>& points(int heading_index, int channel = 0) const {
    return channels_[channel].rotated[heading_index];
  }
  /// Prepared (merged) points at a heading over all channels: the table reads of one score.
  int64_t preparedPoints(int heading_index) const;
  int numHeadings() const { return window_.sizeH(); }
  /// Scan points per heading before merging, over all channels (the n of the log-likelihood).
  int64_t scanPoints() const { return scan_points_; }
  /// Coarsest layer used: the smallest that covers the window in at most a 4 x 4 block grid,
  /// or in a 2 x 2 grid when that is layer 4 or finer; capped by the layers the map holds.
  int topLayer() const { return top_layer_; }

  /// Score (sum of layer values over points, over the channels) of node (j, layer, tx, ty).
  int64_t score(int heading_index, int layer, int tx, int ty) const;
  /// Scores of the four nodes (j, layer, tx + a h, ty + b h), a, b in {0, 1}, in one pass over
  /// the points (the children of a branch-and-bound node): out[b * 2 + a]. Children outside
  /// the window are still scored (the caller skips them).
  void scoreQuad(int heading_index, int layer, int tx, int ty, int h, int64_t out[4]) const;
  /// Base-layer scores of translations tx in [tx0, tx0 + nx), ty in [ty0, ty0 + ny) at heading j,
  /// row-major in ty, into out (resized). Row-contiguous table reads (z-slab-major layout).
  /// point_stride > 1 scores only every point_stride-th prepared point (an estimate for the
  /// covariance, never for the search). Returns the scan points scored (the sum of their merge
  /// counts).
  int64_t scoreBlock(int heading_index, int tx0, int ty0, int nx, int ny, std::vector<int64_t>& out,
                     int point_stride = 1) const;

  /// Pose of translation (tx, ty) and heading j.
  Pose6 pose(int heading_index, int tx, int ty) const;

 private:
  /// One channel: its map's raster over the window and its points per heading.
  struct Channel {
    const ChunkMap* map;
    RasterWindow raster;
    std::vector<std::vector<CellPoint>> rotated;
    int64_t scan_points;
  };
  SearchProblem(const ChunkMap& map, const SearchWindow& w) : map_(&map), window_(w) {}
  static int64_t channelScore(const Channel& ch, int heading_index, int layer, int tx, int ty);
  static void channelScoreQuad(const Channel& ch, int heading_index, int layer, int tx, int ty,
                               int h, int64_t out[4]);
  static int64_t channelScoreBlock(const Channel& ch, int heading_index, int tx0, int ty0, int nx,
                                   int ny, std::vector<int32_t>& acc, int point_stride);

  const ChunkMap* map_;
  SearchWindow window_;
  std::vector<Channel> channels_;
  int64_t scan_points_ = 0;
  int top_layer_ = 0;
};

}  // namespace gmm_localization
