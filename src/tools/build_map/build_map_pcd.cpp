// build_map input: a point-cloud map in PCD files (read by pcd_reader.h, no PCL). Points are
// moved in double (transform, then offset) before narrowing to float; non-finite points and
// points beyond the height limit are dropped and counted.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "build_map/build_map_readers.h"
#include "build_map/pcd_reader.h"

namespace gmm_localization {
namespace tools {
namespace {

namespace fs = std::filesystem;

/// Above 2^17 m the float32 step is 2^-6 m = 1.6 cm; below it, at most 7.8 mm.
constexpr double kFloatCentimetreRangeM = 131072.0;

double floatStepAt(double v) {
  const float f = static_cast<float>(std::abs(v));
  return static_cast<double>(std::nextafter(f, HUGE_VALF)) - f;
}

std::string number(double v, const char* format = "%.6g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

bool hasPcdExtension(const std::string& name) {
  if (name.size() < 4) return false;
  std::string ext = name.substr(name.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".pcd";
}

/// Paths -> files: a directory contributes its *.pcd regular files (symlinks followed), sorted.
Result<std::vector<std::string>> expandPaths(const std::vector<std::string>& paths) {
  using R = Result<std::vector<std::string>>;
  if (paths.empty()) return R::failure("no PCD file given");
  std::vector<std::string> files;
  for (const std::string& p : paths) {
    std::error_code ec;
    if (!fs::is_directory(p, ec)) {
      files.push_back(p);  // PcdFileReader::open reports a missing or unreadable file
      continue;
    }
    std::vector<std::string> found;
    fs::directory_iterator it(p, ec), end;
    for (; !ec && it != end; it.increment(ec)) {
      std::error_code e2;
      if (hasPcdExtension(it->path().filename().string()) && it->is_regular_file(e2))
        found.push_back(it->path().string());
    }
    if (ec) return R::failure("PCD directory '" + p + "': cannot list it: " + ec.message());
    if (found.empty()) return R::failure("PCD directory '" + p + "' holds no *.pcd file");
    std::sort(found.begin(), found.end());
    files.insert(files.end(), found.begin(), found.end());
  }
  return files;
}

std::string describeTransform(const Eigen::Isometry3d& t) {
  const Eigen::Matrix3d r = t.linear();
  const double d = 180.0 / M_PI;
  auto clean = [](double v) { return std::round(v * 1e6) / 1e6 + 0.0; };  // no 1e-15, no -0
  const double roll = std::atan2(r(2, 1), r(2, 2)) * d;
  const double pitch = std::asin(std::max(-1.0, std::min(1.0, -r(2, 0)))) * d;
  const double yaw = std::atan2(r(1, 0), r(0, 0)) * d;
  const Eigen::Vector3d p = t.translation();
  return "transform " + number(clean(p.x())) + "," + number(clean(p.y())) + "," +
         number(clean(p.z())) + " m, rpy " + number(clean(roll)) + "," + number(clean(pitch)) +
         "," + number(clean(yaw)) + " deg";
}

}  // namespace

struct PcdSource::Impl {
  PcdSourceOptions options;
  bool identity = true;  ///< world_T_file is the identity
  std::vector<std::string> files;
  std::vector<uint64_t> file_points;
  std::string first_format;  ///< data kind and fields of the first file
  uint64_t total_points = 0;
  size_t file = 0;                        ///< index of the file being read
  std::unique_ptr<PcdFileReader> reader;  ///< open on files[file], or null
  std::vector<Eigen::Vector3d> xyz;
  std::vector<float> intensity;  ///< of xyz's points, when the file has an intensity field
  uint64_t read = 0, kept = 0, non_finite = 0, out_of_range = 0, far = 0;
  double far_max_m = 0.0;
  bool warned_float = false, ended = false;
  std::vector<std::string> warnings;

  void endWarnings();
};

PcdSource::~PcdSource() = default;

Result<std::unique_ptr<PcdSource>> PcdSource::open(const PcdSourceOptions& options) {
  using R = Result<std::unique_ptr<PcdSource>>;
  if (!(options.max_abs_z_m > 0.0)) return R::failure("PCD input: max |z| must be > 0");
  if (!options.world_T_file.matrix().allFinite() || !options.offset_m.allFinite())
    return R::failure("PCD input: the transform and the offset must be finite");
  auto files = expandPaths(options.paths);
  if (!files) return R::failure(files.error());
  auto src = std::unique_ptr<PcdSource>(new PcdSource());
  src->impl_ = std::make_unique<Impl>();
  Impl& m = *src->impl_;
  m.options = options;
  m.options.batch_points = std::max<size_t>(options.batch_points, 1);
  m.identity = options.world_T_file.matrix().isIdentity(0.0);
  m.files = *files;
  // Check every file before the first point is produced; keep the first one open.
  for (size_t i = 0; i < m.files.size(); ++i) {
    auto r = PcdFileReader::open(m.files[i]);
    if (!r) {
      return R::failure(m.files.size() > 1 ? r.error() + " (file " + std::to_string(i + 1) +
                                                 " of " + std::to_string(m.files.size()) + ")"
                                           : r.error());
    }
    const PcdHeader& h = (*r)->header();
    for (const auto& n : (*r)->notes()) m.warnings.push_back(n);
    m.file_points.push_back(h.points);
    m.total_points += h.points;
    if (i == 0) {
      m.first_format = std::string(PcdHeader::dataName(h.data)) + ", " + h.describeFields();
      m.reader = std::move(*r);
    }
  }
  return R(std::move(src));
}

void PcdSource::Impl::endWarnings() {
  const uint64_t dropped = non_finite + out_of_range;
  if (dropped > 0) {
    std::string w = "dropped " + std::to_string(dropped) + " of " + std::to_string(read) +
                    " points: " + std::to_string(non_finite) + " non-finite, " +
                    std::to_string(out_of_range) + " out of range (map-frame |z| > " +
                    number(options.max_abs_z_m) + " m)";
    if (out_of_range > 0) w += "; see --max-abs-z, and --offset's z when the heights are absolute";
    warnings.push_back(w);
  }
  if (far > 0) {
    warnings.push_back(std::to_string(far) + " points lie more than " +
                       number(kFloatCentimetreRangeM) + " m from the map origin (up to " +
                       number(far_max_m, "%.0f") + " m, where float32 steps are " +
                       number(floatStepAt(far_max_m), "%.3g") +
                       " m): they lose precision; give --offset near the data");
  }
}

Result<bool> PcdSource::next(PointBatch& batch) {
  batch.clear();
  Impl& m = *impl_;
  for (;;) {
    while (!m.reader) {
      if (m.file >= m.files.size()) {
        if (!m.ended) {
          m.ended = true;
          m.endWarnings();
        }
        const std::string what = m.files.size() == 1
                                     ? "PCD map '" + m.files[0] + "'"
                                     : "PCD map (" + std::to_string(m.files.size()) + " files)";
        if (m.read == 0) return Result<bool>::failure(what + ": no point in the data");
        if (m.kept == 0) {
          return Result<bool>::failure(what + ": no point kept (" + std::to_string(m.read) +
                                       " read, " + std::to_string(m.non_finite) + " non-finite, " +
                                       std::to_string(m.out_of_range) + " with map-frame |z| > " +
                                       number(m.options.max_abs_z_m) +
                                       " m: check --offset's z, --transform or --max-abs-z)");
        }
        return false;
      }
      auto r = PcdFileReader::open(m.files[m.file]);  // checked in open(); it may have changed
      if (!r) return Result<bool>::failure(r.error());
      m.reader = std::move(*r);
    }
    m.xyz.clear();
    m.intensity.clear();
    auto n = m.reader->read(m.options.batch_points, m.xyz, &m.intensity);
    if (!n) return Result<bool>::failure(n.error());
    if (*n > 0) break;
    m.reader.reset();  // this file is done
    ++m.file;
  }
  const PcdHeader& h = m.reader->header();
  const int axes[3] = {h.x, h.y, h.z};
  bool is_float32[3];
  for (int k = 0; k < 3; ++k)
    is_float32[k] = h.fields[axes[k]].type == 'F' && h.fields[axes[k]].size == 4;
  const Eigen::Isometry3d& t = m.options.world_T_file;
  batch.points_m.reserve(m.xyz.size());
  const bool with_intensity = m.intensity.size() == m.xyz.size();
  if (with_intensity) batch.intensity.reserve(m.xyz.size());
  for (size_t i = 0; i < m.xyz.size(); ++i) {
    const Eigen::Vector3d& p = m.xyz[i];
    ++m.read;
    if (!p.allFinite()) {
      ++m.non_finite;
      continue;
    }
    if (!m.warned_float) {
      int worst = -1;  // the float32 coordinate of largest magnitude beyond the centimetre range
      for (int k = 0; k < 3; ++k) {
        if (is_float32[k] && std::abs(p[k]) > kFloatCentimetreRangeM &&
            (worst < 0 || std::abs(p[k]) > std::abs(p[worst])))
          worst = k;
      }
      if (worst >= 0) {
        m.warned_float = true;
        m.warnings.push_back(
            "PCD file '" + m.reader->path() + "': " + h.fields[axes[worst]].name +
            " is stored as float32 (F4) and reaches " + number(p[worst], "%.2f") +
            " m, where float32 steps are " + number(floatStepAt(p[worst]), "%.3g") +
            " m: the coordinates are already quantised in the file (--offset cannot restore "
            "them); export the map with F8 (double) x, y, z or in a local frame");
      }
    }
    const Eigen::Vector3d q = (m.identity ? p : Eigen::Vector3d(t * p)) - m.options.offset_m;
    if (!(std::abs(q.z()) <= m.options.max_abs_z_m)) {
      ++m.out_of_range;
      continue;
    }
    const double extent = q.cwiseAbs().maxCoeff();
    if (extent > kFloatCentimetreRangeM) {
      ++m.far;
      m.far_max_m = std::max(m.far_max_m, extent);
    }
    batch.points_m.emplace_back(q.cast<float>());
    if (with_intensity) batch.intensity.push_back(m.intensity[i]);
    ++m.kept;
  }
  return true;  // possibly empty, when every point of the batch was dropped
}

size_t PcdSource::sizeHint() const {
  const size_t b = impl_->options.batch_points;
  size_t n = 0;
  for (uint64_t p : impl_->file_points) n += static_cast<size_t>((p + b - 1) / b);
  return n;
}

size_t PcdSource::points() const { return static_cast<size_t>(impl_->total_points); }

const std::vector<std::string>& PcdSource::files() const { return impl_->files; }

uint64_t PcdSource::droppedPoints() const { return impl_->non_finite + impl_->out_of_range; }

std::string PcdSource::dropped() const {
  const Impl& m = *impl_;
  if (droppedPoints() == 0) return "none";
  return std::to_string(droppedPoints()) + " (" + std::to_string(m.non_finite) + " non-finite, " +
         std::to_string(m.out_of_range) + " with map-frame |z| > " + number(m.options.max_abs_z_m) +
         " m)";
}

std::vector<std::string> PcdSource::takeWarnings() {
  std::vector<std::string> w;
  w.swap(impl_->warnings);
  return w;
}

std::string PcdSource::describe() const {
  const Impl& m = *impl_;
  std::string s;
  if (m.files.size() == 1) {
    s = "PCD map '" + m.files[0] + "' (" + std::to_string(m.total_points) + " points, " +
        m.first_format + ")";
  } else {
    std::string given;
    for (size_t i = 0; i < m.options.paths.size() && i < 3; ++i)
      given += (i ? ", '" : "'") + m.options.paths[i] + "'";
    if (m.options.paths.size() > 3) given += ", ...";
    s = "PCD map from " + given + " (" + std::to_string(m.files.size()) + " files, " +
        std::to_string(m.total_points) + " points)";
  }
  if (!m.identity) s += ", " + describeTransform(m.options.world_T_file);
  return s;
}

}  // namespace tools
}  // namespace gmm_localization
