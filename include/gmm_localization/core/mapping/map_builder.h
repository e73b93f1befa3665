#pragma once
// The offline Gaussian mixture map builder (paper section III): points in the map frame ->
// per-cell z columns -> Gaussian blur with neighbouring columns (as weights) -> weighted EM per
// cell with model selection -> compact tiles + manifest on disk.
//
// Streaming, in two passes, so memory does not grow with the size of the map:
//  1. addBatch() filters each batch and bins its points, as (cell, z-bin, count) records, into
//     one spill file per tile in a temporary directory (in the staging directory, see below). A
//     point within blur_radius_cells of a tile border is also written to the neighbouring tiles'
//     spill files (a halo), so each tile can later be processed alone. Records are buffered per
//     tile, merged (same cell and z bin: one record with a count) and appended to disk when a
//     buffer fills; at most spill_buffer_bytes are held in memory.
//  2. finish() processes the tiles one at a time on `threads` worker threads: read the tile's
//     spill file, build each column's z histogram, blur, fit, encode and write the tile file
//     (atomically) into the staging directory, then delete the spill file. Last, the new map is
//     swapped into the output directory; its manifest is the commit: a directory without a
//     manifest is not a map.
// Only one tile's histogram per worker is ever in memory.
//
// The blur (paper: "to capture the variance of our LIDAR scanner and reduce discretization
// errors, we blur these z-points with neighboring columns with a Gaussian kernel"): the samples
// of cell c are the z bins of every column c' with |c' - c|_inf <= blur_radius_cells, weighted
// by exp(-|center(c') - center(c)|^2 / (2 blur_sigma_m^2)) (1 for c itself). Default sigma
// 0.10 m: a point's position within a 20 cm cell is uncertain by 0.2/sqrt(12) = 5.8 cm per
// axis, plus ~2 cm range noise and a few cm of map pose error, i.e. ~7-10 cm; a radius of one
// cell then holds every weight above exp(-4) = 0.018. A cell with fewer than min_own_points
// returns in its own column stays empty: the blur reshapes observed cells, it never invents
// map where nothing was seen.
//
// z binning: heights are binned at z_bin_m (1 cm, error <= 5 mm, adding (1 cm)^2/12 of
// variance: negligible against the 3 cm sigma floor). A cell with more than
// max_samples_per_cell distinct bins after the blur (tall walls) has adjacent bins merged
// (keeping each merged sample at its weighted centroid) until it fits, which bounds EM's cost.
//
// Layers (core/map/reflectivity_layer.h; the manifest records which): the height layer, the
// paper's map, bins each kept point's z. The reflectivity layer (Levinson and Thrun's ground
// reflectivity, the baseline of the paper's Table I) keeps the ground returns only and bins
// their value v = intensity * metres_per_unit in place of z; "z" and "height" in the binning,
// blur and fit below then mean v, and everything else (tiles, EM, swap) is the same. Its
// batches must carry one intensity per point and a vehicle origin (MapBuilderOptions::
// batchError): a batch without either fails addBatch with the reason.
//
// Filters, applied per point in this order (each counted in MapBuildStats):
//  - non-finite coordinates, and points beyond 1e7 m of the grid origin or 1e6 m in height
//    (no map frame is that large; keep coordinates local), are dropped; in the reflectivity
//    layer also a non-finite intensity or a value beyond 1e6 m;
//  - range: distance from the batch's sensor origin outside [min_range_m, max_range_m] is
//    dropped (vehicle self-returns, far and sparse returns). Batches without a sensor origin
//    (a point-cloud map) are not range-filtered;
//  - height band: map-frame z outside [min_z_m, max_z_m] is dropped (in both layers: z is the
//    point's height);
//  - ground (reflectivity layer only): a point that is not a ground return
//    (ReflectivityLayerOptions::isGround on its z minus the vehicle origin's z and its
//    horizontal distance to the vehicle origin) is dropped;
//  - voxel pre-filter (voxel_m > 0): within one batch, only the first point of each
//    voxel_m-sized cube is kept, which evens out the density near the sensor. Off by default.
//
// Threading: addBatch() and finish() must be called from one thread (the caller's); finish()
// uses worker threads internally and calls the progress callback from the caller's thread.
// finish() joins its workers before it returns, on every path. A worker's failure (an I/O error,
// an exception such as std::bad_alloc), a progress callback that throws, or threads that cannot
// be started fail the build with a reason like any other error; no exception leaves the
// builder's API (create, addBatch, finish, addAllBatches), and nothing calls std::terminate.
//
// Replacing a map: a build never writes into the map in place. create() takes an exclusive
// flock(2) on the output directory (a second builder of the same directory, in any process,
// fails) and makes the staging directory `<output>/.gmm_build.<pid>.<n>/`, which receives the
// spill files (unless temp_directory is set) and the new tile files. finish() then swaps:
//  1. it names the new tiles `tile_<tx>_<ty>.gmt`, or, when the map in place uses those names
//     (an overwrite), `tile_<tx>_<ty>.g1.gmt` (g2, ... should those be taken too): rebuilt maps
//     alternate between the two sets of names. Readers take each tile's file name from the
//     manifest (TileInfo::file_name), so old and new maps load alike;
//  2. it writes the journal `<staging>/journal`: the line "gmm_build journal 1", then one file
//     name per line, the new tiles' and the old map's tiles';
//  3. it moves the tiles into the output directory (rename(2), same file system; none of the
//     names is the old map's) and fsyncs the directory;
//  4. it writes the new manifest into staging as `manifest.next` and renames it over
//     `<output>/manifest.gmm`. That one rename is the commit: before it the directory holds the
//     old map, byte-identical, after it the new one, complete;
//  5. it deletes the old map's tile files, then the staging directory.
// A failure before the commit (I/O error, full disk, cancel, no points, the staging directory
// removed by someone else mid-build) removes what the build moved in and its staging directory:
// the output directory is as it was. A process killed outright leaves its staging directory;
// the next create() on that directory (holding the lock, it knows the owner is gone) deletes
// every file the journal names that the manifest then in place does not reference, which undoes
// a half-done step 3 or completes step 5, and then the staging directory. A staging directory
// never holds a `manifest.gmm`, and MapStore reads only the files its manifest names, so a
// half-written build is never taken for a map. Where flock is not supported (some network file
// systems) there is no lock, and only staging directories whose process no longer exists are
// recovered. A process that opened the old map (MapStore reads the manifest once) sees its tiles
// vanish at step 5: restart it on the new map.
// Disk space: until the commit, the old map, the new map and the spill files coexist; a full disk
// fails the build with an error starting "no space left on device", the old map intact.
//
// Failure: every method returns a Status/Result with a reason; the destructor removes the
// staging and spill directories whatever happened. create() also removes the spill directories
// (`.gmm_build_spill.<pid>.<n>`, in temp_directory or, from older versions, in the output
// directory) of processes that are gone.

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/map_format.h"
#include "gmm_localization/core/map/map_geometry.h"
#include "gmm_localization/core/map/reflectivity_layer.h"
#include "gmm_localization/core/mapping/em_fitter.h"
#include "gmm_localization/core/mapping/point_batch.h"

namespace gmm_localization {

struct MapBuilderOptions {
  std::string output_directory;  ///< created if missing
  /// Replace a map already there. The old map stays whole until the new one is complete and
  /// swapped in (see "Replacing a map"); false: create() fails when the directory holds a map.
  bool overwrite = false;
  MapGeometry geometry;  ///< resolution (paper: 20 cm), tile size, origin
  EmFitterOptions em;    ///< K_max (default 2), sigma floor, criterion

  double blur_sigma_m = 0.10;      ///< Gaussian kernel sigma [m], >= 0 (0: no blur)
  int blur_radius_cells = 1;       ///< kernel half-width [cells], in [0, min(8, tile size / 4)]
  double z_bin_m = 0.01;           ///< z histogram bin [m], in [1e-4, 0.1]
  int max_samples_per_cell = 256;  ///< distinct z samples per fit, in [16, 65536]
  int min_own_points = 1;          ///< returns needed in a cell's own column, >= 0

  double min_range_m = 1.0;                                   ///< [m], >= 0
  double max_range_m = 120.0;                                 ///< [m], > min_range_m
  double min_z_m = -std::numeric_limits<double>::infinity();  ///< map-frame height band [m]
  double max_z_m = std::numeric_limits<double>::infinity();
  double voxel_m = 0.0;  ///< per-batch voxel filter edge [m], 0 = off, else >= 0.005

  int threads = 2;             ///< worker threads in finish(), in [1, 64]
  std::string temp_directory;  ///< parent of the spill directory; empty: the staging directory
  size_t spill_buffer_bytes = size_t{256} << 20;  ///< in-memory spill buffers, >= 1 MiB
  TileCodecOptions codec;
  Georeference georeference;  ///< written to the manifest
  std::string provenance;     ///< written to the manifest (inputs, tool, options)

  MapLayer layer = MapLayer::kHeight;     ///< what the cells hold; written to the manifest
  ReflectivityLayerOptions reflectivity;  ///< layer kReflectivity: ground returns and scale

  /// Empty when valid, else the first offending field, its value and the allowed range.
  std::string validate() const;
  /// One line with the options that shape the map (for provenance and logs), the layer too.
  std::string describe() const;
  /// Empty when `batch` carries what the layer needs, else what it lacks (one sentence): the
  /// reflectivity layer needs one intensity per point and a vehicle origin (an empty batch
  /// needs nothing); the height layer needs nothing beyond the points. A reader's caller may
  /// check it first to name the input in the reason (addAllBatches does).
  std::string batchError(const PointBatch& batch) const;
};

struct MapBuildStats {
  uint64_t batches = 0;
  uint64_t batches_without_origin = 0;  ///< not range-filtered
  uint64_t input_points = 0;
  uint64_t kept_points = 0;
  uint64_t dropped_invalid = 0;  ///< non-finite, or beyond 1e7 m from the origin / |z| > 1e6 m
  uint64_t dropped_range = 0;
  uint64_t dropped_height = 0;
  uint64_t dropped_voxel = 0;
  uint64_t dropped_not_ground = 0;  ///< reflectivity layer: not a ground return
  uint64_t spill_bytes = 0;         ///< written to the spill directory
  uint64_t tiles = 0;               ///< tile files written
  std::array<uint64_t, kMaxMixtureComponents + 1> cells_by_components{};  ///< over written tiles
  uint64_t map_bytes = 0;  ///< tile files + manifest [bytes]
  EmFitterCounters em;     ///< EM work over all cells (fits, runs, iterations, samples)
};

struct BuildProgress {
  enum class Stage { kFitting, kDone };
  Stage stage = Stage::kFitting;
  uint64_t tiles_done = 0;
  uint64_t tiles_total = 0;
  uint64_t work_done = 0;  ///< spill bytes of the finished tiles (a proxy for fitting work)
  uint64_t work_total = 0;
};
/// Called from finish()'s calling thread after every tile; return false to cancel the build.
/// An exception it throws fails the build (before the commit) or is ignored (the kDone call).
using BuildProgressCallback = std::function<bool(const BuildProgress&)>;

class MapBuilder {
 public:
  /// Validates the options, creates the output directory, locks it, recovers the leftovers of
  /// killed builds there, and creates the staging and spill directories. Fails when the output
  /// already holds a map and overwrite is false, or when another builder holds the directory.
  static Result<std::unique_ptr<MapBuilder>> create(const MapBuilderOptions& options);
  ~MapBuilder();  // removes the staging and spill directories, releases the lock
  MapBuilder(const MapBuilder&) = delete;
  MapBuilder& operator=(const MapBuilder&) = delete;

  /// Pass 1 for one batch. Fails on a spill write error (the builder is then unusable, and its
  /// staging directory already removed), and, before any point is taken (the builder stays
  /// usable), on a batch that lacks what the layer needs (options().batchError).
  Status addBatch(const PointBatch& batch);

  /// Pass 2 and the swap. Call once; the builder is spent afterwards (and the lock released).
  /// Fails, leaving the output directory as it was, when no point was kept, on I/O errors
  /// (the staging directory vanishing included), when the callback cancels or throws, or when
  /// the directory gained a map meanwhile and overwrite is false. Joins its worker threads
  /// before returning, whatever happened.
  Result<MapBuildStats> finish(const BuildProgressCallback& progress = {});

  /// Counters so far (pass 1 counters grow with addBatch; the rest are set by finish()).
  const MapBuildStats& stats() const;
  const MapBuilderOptions& options() const;

 private:
  struct Impl;
  explicit MapBuilder(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// Reads every batch of `source` into `builder`. `on_batch(done, total)` is called after each
/// batch (total = source.sizeHint(), 0 when unknown); return false from it to stop early (not
/// an error). Fails on the first source or builder failure; a batch that lacks what the layer
/// needs fails with a reason naming the source (source.describe()) and the batch.
Status addAllBatches(PointBatchSource& source, MapBuilder& builder,
                     const std::function<bool(size_t done, size_t total)>& on_batch = {});

}  // namespace gmm_localization
