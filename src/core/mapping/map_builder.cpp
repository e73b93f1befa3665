// Map builder: options, creation, and pass 1 (filter and bin points into per-tile spill files).
#include "gmm_localization/core/mapping/map_builder.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <sstream>

#include "map_builder_impl.h"

namespace gmm_localization {
namespace {

namespace fs = std::filesystem;
using map_builder::SpillRecord;

constexpr double kMaxHorizontalM = 1e7;
constexpr double kMaxAbsInputHeightM = 1e6;

std::string fieldError(const char* name, double value, const std::string& range) {
  std::ostringstream s;
  s << name << "=" << value << " must be in " << range;
  return s.str();
}

uint64_t voxelKey(double x, double y, double z, double v) {
  constexpr uint64_t kMask = (uint64_t{1} << 21) - 1;  // wraps only 2^21 voxels apart
  const auto ix = static_cast<uint64_t>(static_cast<int64_t>(std::floor(x / v))) & kMask;
  const auto iy = static_cast<uint64_t>(static_cast<int64_t>(std::floor(y / v))) & kMask;
  const auto iz = static_cast<uint64_t>(static_cast<int64_t>(std::floor(z / v))) & kMask;
  return ix | (iy << 21) | (iz << 42);
}

/// Removes spill directories left in `parent` by builds whose process no longer exists
/// (killed before their destructor ran).
void removeStaleSpillDirectories(const std::string& parent) {
  const std::string prefix = ".gmm_build_spill.";
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(parent, ec)) {
    const std::string name = entry.path().filename();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
      fs::remove_all(entry.path(), ec);
    }
  }
}

}  // namespace

std::string MapBuilderOptions::validate() const {
  if (output_directory.empty()) return "output_directory must not be empty";
  const std::string g = geometry.validate();
  if (!g.empty()) return "geometry: " + g;
  const std::string e = em.validate();
  if (!e.empty()) return "em: " + e;
  if (!(blur_sigma_m >= 0.0 && blur_sigma_m <= 10.0)) {
    return fieldError("blur_sigma_m", blur_sigma_m, "[0, 10] m");
  }
  const int max_radius = std::min(8, geometry.tile_size_cells / 4);
  if (blur_radius_cells < 0 || blur_radius_cells > max_radius) {
    return fieldError("blur_radius_cells", blur_radius_cells,
                      "[0, min(8, tile_size_cells / 4) = " + std::to_string(max_radius) + "]");
  }
  if (!(z_bin_m >= 1e-4 && z_bin_m <= 0.1)) return fieldError("z_bin_m", z_bin_m, "[1e-4, 0.1] m");
  if (max_samples_per_cell < 16 || max_samples_per_cell > 65536) {
    return fieldError("max_samples_per_cell", max_samples_per_cell, "[16, 65536]");
  }
  if (min_own_points < 0 || min_own_points > 1000000) {
    return fieldError("min_own_points", min_own_points, "[0, 1e6]");
  }
  if (!(min_range_m >= 0.0) || std::isinf(min_range_m)) {
    return fieldError("min_range_m", min_range_m, "[0, inf) m");
  }
  if (!(max_range_m > min_range_m))
    return fieldError("max_range_m", max_range_m, "(min_range_m, inf] m");
  if (!(min_z_m < max_z_m)) return fieldError("max_z_m", max_z_m, "(min_z_m, inf] m");
  if (!(voxel_m == 0.0 || (voxel_m >= 0.005 && voxel_m <= 10.0))) {
    return fieldError("voxel_m", voxel_m, "{0} or [0.005, 10] m");
  }
  if (threads < 1 || threads > 64) return fieldError("threads", threads, "[1, 64]");
  if (spill_buffer_bytes < (size_t{1} << 20)) {
    return fieldError("spill_buffer_bytes", static_cast<double>(spill_buffer_bytes),
                      "[1 MiB, inf)");
  }
  if (codec.deflate_level < 1 || codec.deflate_level > 9) {
    return fieldError("codec.deflate_level", codec.deflate_level, "[1, 9]");
  }
  if (layer != MapLayer::kHeight && layer != MapLayer::kReflectivity) {
    return fieldError("layer", static_cast<int>(layer), "{0 height, 1 reflectivity}");
  }
  if (layer == MapLayer::kReflectivity) {
    const std::string r = checkReflectivityLayer(reflectivity);
    if (!r.empty()) return "reflectivity." + r;
  }
  return {};
}

std::string MapBuilderOptions::batchError(const PointBatch& batch) const {
  if (layer != MapLayer::kReflectivity || batch.points_m.empty()) return {};
  if (batch.intensity.empty()) {
    return "no intensity: the reflectivity layer maps each ground return's intensity, and the "
           "input gives none";
  }
  if (batch.intensity.size() != batch.points_m.size()) {
    return std::to_string(batch.intensity.size()) + " intensities for " +
           std::to_string(batch.points_m.size()) + " points";
  }
  if (!batch.has_vehicle_origin) {
    return "no vehicle pose: the reflectivity layer selects ground returns by their height "
           "above the vehicle frame (a point-cloud map has none)";
  }
  if (!batch.vehicle_origin_m.allFinite()) return "the vehicle origin is not finite";
  return {};
}

std::string MapBuilderOptions::describe() const {
  std::ostringstream s;
  s << "resolution=" << geometry.resolution_m << "m tile=" << geometry.tile_size_cells
    << "cells origin=(" << geometry.origin_x_m << "," << geometry.origin_y_m
    << ") K_max=" << em.max_components << " criterion=" << toString(em.criterion)
    << " sigma_floor=" << em.sigma_floor_m << "m blur_sigma=" << blur_sigma_m
    << "m blur_radius=" << blur_radius_cells << " z_bin=" << z_bin_m
    << "m min_own_points=" << min_own_points << " range=[" << min_range_m << "," << max_range_m
    << "]m z=[" << min_z_m << "," << max_z_m << "]m voxel=" << voxel_m
    << "m layer=" << mapLayerName(layer);
  if (layer == MapLayer::kReflectivity) {
    s << " metres_per_unit=" << reflectivity.metres_per_unit
      << " ground_height=" << reflectivity.ground_height_m << "m ground_band=["
      << reflectivity.ground_min_m << "," << reflectivity.ground_max_m
      << "]m ground_range=" << reflectivity.max_range_m << "m";
  }
  return s.str();
}

MapBuilder::MapBuilder(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

MapBuilder::~MapBuilder() { impl_->abandon(); }

void MapBuilder::Impl::removeSpillDirectory() {
  spill.reset();
  if (spill_directory.empty()) return;
  std::error_code ec;
  fs::remove_all(spill_directory, ec);
  spill_directory.clear();
}

void MapBuilder::Impl::abandon() {
  removeSpillDirectory();
  if (!staging_directory.empty()) {
    std::error_code ec;
    fs::remove_all(staging_directory, ec);
    staging_directory.clear();
  }
  lock.release();
}

std::string MapBuilder::Impl::explain(const std::string& error) const {
  if (error.find(std::strerror(ENOSPC)) != std::string::npos) {
    return "no space left on device: " + error +
           " (a build needs room for its spill files and for the new map beside the old one; '" +
           options.output_directory + "' is left as it was)";
  }
  std::error_code ec;
  if (!staging_directory.empty() && !fs::exists(staging_directory, ec) && !ec) {
    return "the build's staging directory '" + staging_directory +
           "' disappeared during the build (removed by another program?): " + error + " ('" +
           options.output_directory + "' is left as it was)";
  }
  return error;
}

std::string MapBuilder::Impl::failWith(const std::string& error) {
  failure = explain(error);  // before abandon(): it looks at the staging directory
  abandon();
  return failure;
}

const MapBuildStats& MapBuilder::stats() const { return impl_->stats; }
const MapBuilderOptions& MapBuilder::options() const { return impl_->options; }

Result<std::unique_ptr<MapBuilder>> MapBuilder::create(const MapBuilderOptions& options) {
  try {
    return Impl::create(options);
  } catch (...) {  // what create() had made went with its Impl (~Impl abandons)
    return Result<std::unique_ptr<MapBuilder>>::failure("cannot create the map builder: " +
                                                        currentExceptionText());
  }
}

Status MapBuilder::addBatch(const PointBatch& batch) {
  try {
    return impl_->addBatch(batch);
  } catch (...) {  // the spill buffers may be half updated: the builder is unusable
    return Status::failure(
        impl_->failWith("map builder: adding a batch failed: " + currentExceptionText()));
  }
}

Result<std::unique_ptr<MapBuilder>> MapBuilder::Impl::create(const MapBuilderOptions& options) {
  using R = Result<std::unique_ptr<MapBuilder>>;
  const std::string invalid = options.validate();
  if (!invalid.empty()) return R::failure("invalid map builder options: " + invalid);
  const std::string& dir = options.output_directory;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    return R::failure("cannot create output directory '" + dir +
                      "': " + (ec ? ec.message() : std::string("not a directory")));
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  if (impl->lock.tryLock(dir) == map_builder::DirectoryLock::Outcome::kBusy) {
    return R::failure("output directory '" + dir +
                      "' is in use by another map build (it holds the directory's lock)");
  }
  const std::string manifest = dir + "/" + kManifestFileName;
  if (fs::exists(manifest, ec) && !options.overwrite) {
    return R::failure("output directory '" + dir + "' already holds a map (" + kManifestFileName +
                      "); set overwrite (build_map: --overwrite)");
  }
  // Leftovers of builds that were killed: their staging directories (undoing a half-done
  // swap), and spill directories of this and of older versions.
  map_builder::recoverStagingDirectories(dir, impl->lock.held());
  removeStaleSpillDirectories(dir);
  auto staging = map_builder::createStagingDirectory(dir);
  if (!staging) return R::failure(impl->explain(staging.error()));
  impl->staging_directory = *staging;
  if (options.temp_directory.empty()) {
    impl->spill_directory = impl->staging_directory + "/spill";
  } else {
    static std::atomic<uint64_t> counter{0};
    removeStaleSpillDirectories(options.temp_directory);
    impl->spill_directory = options.temp_directory + "/.gmm_build_spill." +
                            std::to_string(getpid()) + "." + std::to_string(counter.fetch_add(1));
  }
  if (!fs::create_directories(impl->spill_directory, ec) || ec) {
    const std::string why = "cannot create temporary directory '" + impl->spill_directory +
                            "': " + (ec ? ec.message() : std::string("it already exists"));
    impl->abandon();
    return R::failure(impl->explain(why));
  }
  impl->spill =
      std::make_unique<map_builder::SpillStore>(impl->spill_directory, options.spill_buffer_bytes);
  return std::unique_ptr<MapBuilder>(new MapBuilder(std::move(impl)));
}

Status MapBuilder::Impl::binPoint(double x, double y, double z) {
  const MapGeometry& g = options.geometry;
  const CellIndex c = g.cellAt(x, y);
  const TileId t = g.tileOf(c);
  const CellIndex o = g.tileOrigin(t);
  const int size = g.tile_size_cells, r = options.blur_radius_cells, extent = size + 2 * r;
  const int lx = static_cast<int>(c.x - o.x), ly = static_cast<int>(c.y - o.y);
  const auto zbin = static_cast<int32_t>(std::floor(z / options.z_bin_m));
  if (t != last_tile || last_buffer == nullptr) {
    own_tiles.insert(t);
    last_tile = t;
    last_buffer = &spill->buffer(t);
  }
  last_buffer->push_back({static_cast<uint16_t>(lx + r), static_cast<uint16_t>(ly + r), zbin, 1});
  Status s = spill->afterAppend(t, *last_buffer, 1);
  if (!s || r == 0) return s;
  if (lx >= r && lx < size - r && ly >= r && ly < size - r) return s;
  // Halo: the neighbouring tiles whose extended (size + 2r) square holds this column.
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx == 0 && dy == 0) continue;
      const int ex = lx - dx * size + r, ey = ly - dy * size + r;
      if (ex < 0 || ex >= extent || ey < 0 || ey >= extent) continue;
      const TileId n{t.x + dx, t.y + dy};
      auto& buffer = spill->buffer(n);
      buffer.push_back({static_cast<uint16_t>(ex), static_cast<uint16_t>(ey), zbin, 1});
      s = spill->afterAppend(n, buffer, 1);
      if (!s) return s;
    }
  }
  return s;
}

Status MapBuilder::Impl::addBatch(const PointBatch& batch) {
  Impl& m = *this;
  if (!m.failure.empty()) return Status::failure("map builder unusable: " + m.failure);
  if (m.finished) return Status::failure("map builder: addBatch after finish");
  const MapBuilderOptions& o = m.options;
  const std::string lacking = o.batchError(batch);
  if (!lacking.empty()) {  // nothing taken: the builder stays usable
    return Status::failure("map builder (" + std::string(mapLayerName(o.layer)) +
                           " layer): batch " + std::to_string(m.stats.batches + 1) + ": " +
                           lacking);
  }
  MapBuildStats& st = m.stats;
  ++st.batches;
  if (!batch.has_sensor_origin) ++st.batches_without_origin;
  const bool range = batch.has_sensor_origin && batch.sensor_origin_m.allFinite();
  const double r_lo2 = o.min_range_m * o.min_range_m, r_hi2 = o.max_range_m * o.max_range_m;
  const Eigen::Vector3d& s = batch.sensor_origin_m;
  // The reflectivity layer bins v = intensity * metres_per_unit (reflectivity_layer.h) of the
  // ground returns; the height layer bins z, and reads nothing else of the batch.
  const bool reflectivity = o.layer == MapLayer::kReflectivity;
  const ReflectivityLayerOptions& refl = o.reflectivity;
  const Eigen::Vector3d& vehicle = batch.vehicle_origin_m;
  if (o.voxel_m > 0.0) m.voxels.clear();
  for (size_t i = 0; i < batch.points_m.size(); ++i) {
    const Eigen::Vector3f& pf = batch.points_m[i];
    ++st.input_points;
    const double x = pf.x(), y = pf.y(), z = pf.z();
    const double value = reflectivity ? refl.value(batch.intensity[i]) : z;
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) || !std::isfinite(value) ||
        std::abs(x - o.geometry.origin_x_m) > kMaxHorizontalM ||
        std::abs(y - o.geometry.origin_y_m) > kMaxHorizontalM ||
        std::abs(z) > kMaxAbsInputHeightM || std::abs(value) > kMaxAbsInputHeightM) {
      ++st.dropped_invalid;
      continue;
    }
    if (range) {
      const double d2 =
          (x - s.x()) * (x - s.x()) + (y - s.y()) * (y - s.y()) + (z - s.z()) * (z - s.z());
      if (d2 < r_lo2 || d2 > r_hi2) {
        ++st.dropped_range;
        continue;
      }
    }
    if (z < o.min_z_m || z > o.max_z_m) {
      ++st.dropped_height;
      continue;
    }
    if (reflectivity &&
        !refl.isGround(z - vehicle.z(), std::hypot(x - vehicle.x(), y - vehicle.y()))) {
      ++st.dropped_not_ground;
      continue;
    }
    if (o.voxel_m > 0.0 && !m.voxels.insert(voxelKey(x, y, z, o.voxel_m)).second) {
      ++st.dropped_voxel;
      continue;
    }
    ++st.kept_points;
    Status bs = m.binPoint(x, y, value);
    if (!bs) {
      // Frees the disk at once; the output directory is as it was.
      return Status::failure(m.failWith(bs.error()));
    }
  }
  return Status::success();
}

Status addAllBatches(PointBatchSource& source, MapBuilder& builder,
                     const std::function<bool(size_t, size_t)>& on_batch) {
  // builder.addBatch() throws nothing; an exception from the source or from on_batch is a
  // failure (the builder stays usable).
  try {
    PointBatch batch;
    const size_t total = source.sizeHint();
    for (size_t done = 0;;) {
      auto more = source.next(batch);
      if (!more) return Status::failure(more.error());
      if (!*more) return Status::success();
      const std::string lacking = builder.options().batchError(batch);
      if (!lacking.empty()) {
        return Status::failure(source.describe() + ": batch " + std::to_string(done + 1) + ": " +
                               lacking);
      }
      Status s = builder.addBatch(batch);
      if (!s) return s;
      ++done;
      if (on_batch && !on_batch(done, total)) return Status::success();
    }
  } catch (...) {
    return Status::failure("adding the point source's batches failed: " + currentExceptionText());
  }
}

}  // namespace gmm_localization
