// Map format: the tile codec (layout and quantisation documented in map_format.h).
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "gmm_localization/core/map/map_format.h"
#include "map_format_bytes.h"

namespace gmm_localization {
namespace {

using map_format::ByteReader;
using map_format::ByteWriter;

constexpr uint8_t kTileMagic[4] = {'G', 'M', 'M', 'T'};
constexpr size_t kTileHeaderBytes = 48;
constexpr size_t kCrcBytes = 4;
constexpr uint16_t kFlagDeflate = 1;
constexpr int kSlots = kMaxMixtureComponents;
constexpr double kMeanQuantumMinM = 1e-3;
constexpr double kCodeMax = 65535.0;
const double kLogSigmaLo = std::log(1e-4), kLogSigmaHi = std::log(1e4);
const double kLogWeightLo = std::log(std::ldexp(1.0, -20));

uint16_t sigmaCode(double s) {
  return static_cast<uint16_t>(
      std::lround((std::log(s) - kLogSigmaLo) / (kLogSigmaHi - kLogSigmaLo) * kCodeMax));
}
double sigmaValue(uint16_t c) {
  return std::exp(kLogSigmaLo + (kLogSigmaHi - kLogSigmaLo) * (c / kCodeMax));
}
uint16_t weightCode(double w) {
  return static_cast<uint16_t>(
      std::lround((std::log(w) - kLogWeightLo) / -kLogWeightLo * kCodeMax));
}
double weightValue(uint16_t c) { return std::exp(kLogWeightLo * (1.0 - c / kCodeMax)); }

/// u16 values as a plane of low bytes then a plane of high bytes.
void putPlanes(std::vector<uint8_t>& out, const std::vector<uint16_t>& v) {
  for (uint16_t x : v) out.push_back(static_cast<uint8_t>(x & 0xff));
  for (uint16_t x : v) out.push_back(static_cast<uint8_t>(x >> 8));
}
std::vector<uint16_t> getPlanes(const uint8_t* p, size_t n) {
  std::vector<uint16_t> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = static_cast<uint16_t>(p[i] | (p[n + i] << 8));
  return v;
}

std::string cellName(const GmmTile& t, size_t i) {
  return "cell (" + std::to_string(i % t.sizeCells()) + ", " + std::to_string(i / t.sizeCells()) +
         ") of tile (" + std::to_string(t.id().x) + ", " + std::to_string(t.id().y) + ")";
}

}  // namespace

TileInfo summarizeTile(const GmmTile& tile) {
  TileInfo info;
  info.id = tile.id();
  float lo = INFINITY, hi = -INFINITY;
  for (const GaussianMixture1D& g : tile.cells()) {
    ++info.cells_by_components[g.size()];
    for (int j = 0; j < g.size(); ++j) {
      lo = std::min(lo, g.component(j).mean_m - 4.f * g.component(j).sigma_m);
      hi = std::max(hi, g.component(j).mean_m + 4.f * g.component(j).sigma_m);
    }
  }
  if (lo <= hi) {
    info.z_min_m = lo;
    info.z_max_m = hi;
  }
  return info;
}

Result<EncodedTile> encodeTile(const GmmTile& tile, const TileCodecOptions& options) {
  using R = Result<EncodedTile>;
  const int32_t size = tile.sizeCells();
  if (size < 8 || size > 4096)
    return R::failure("tile size " + std::to_string(size) + " not in [8, 4096]");
  const auto& cells = tile.cells();
  double mu_lo = INFINITY, mu_hi = -INFINITY;
  uint32_t total = 0;
  for (size_t i = 0; i < cells.size(); ++i) {
    const GaussianMixture1D& g = cells[i];
    for (int j = 0; j < g.size(); ++j) {
      const GaussianComponent& c = g.component(j);
      if (!std::isfinite(c.mean_m)) {
        return R::failure("cannot encode " + cellName(tile, i) + ": mean is not finite");
      }
      if (std::abs(c.mean_m) > kMaxMapHeightM) {
        return R::failure("cannot encode " + cellName(tile, i) + ": mean " +
                          std::to_string(c.mean_m) + " m beyond the physical height range");
      }
      if (!(c.sigma_m >= 1e-4f && c.sigma_m <= kMaxComponentSigmaM)) {
        return R::failure("cannot encode " + cellName(tile, i) + ": sigma " +
                          std::to_string(c.sigma_m) + " m outside [1e-4, " +
                          std::to_string(kMaxComponentSigmaM) + "]");
      }
      if (g.size() >= 2 && !(c.weight >= std::ldexp(1.f, -20) && c.weight <= 1.f)) {
        return R::failure("cannot encode " + cellName(tile, i) + ": weight " +
                          std::to_string(c.weight) + " outside [2^-20, 1]");
      }
      mu_lo = std::min<double>(mu_lo, c.mean_m);
      mu_hi = std::max<double>(mu_hi, c.mean_m);
      ++total;
    }
  }
  const double base = total ? mu_lo : 0.0;
  double quantum = total ? std::max(kMeanQuantumMinM, (mu_hi - mu_lo) / (kCodeMax - 1.0)) : 1e-3;

  std::vector<uint8_t> raw((cells.size() + 3) / 4, 0);
  for (size_t i = 0; i < cells.size(); ++i) {
    raw[i / 4] |= static_cast<uint8_t>(cells[i].size() << (2 * (i % 4)));
  }
  for (int field = 0; field < 3; ++field) {  // 0 mean, 1 sigma, 2 weight
    for (int j = 0; j < kMaxMixtureComponents; ++j) {
      std::vector<uint16_t> codes;
      uint16_t prev = 0;
      for (const GaussianMixture1D& g : cells) {
        if (g.size() <= j || (field == 2 && g.size() < 2)) continue;
        const GaussianComponent& c = g.component(j);
        uint16_t code;
        if (field == 0) {
          code = static_cast<uint16_t>(
              std::clamp<long>(std::lround((c.mean_m - base) / quantum), 0, 65535));
        } else if (field == 1) {
          code = sigmaCode(c.sigma_m);
        } else {
          code = weightCode(c.weight);
        }
        if (field < 2) {  // delta from the previous code of the slot, mod 2^16
          const uint16_t delta = static_cast<uint16_t>(code - prev);
          prev = code;
          code = delta;
        }
        codes.push_back(code);
      }
      putPlanes(raw, codes);
    }
  }

  std::vector<uint8_t> stored;
  uint16_t flags = 0;
  if (options.deflate && !raw.empty()) {
    uLongf bound = compressBound(static_cast<uLong>(raw.size()));
    stored.resize(bound);
    if (compress2(stored.data(), &bound, raw.data(), static_cast<uLong>(raw.size()),
                  std::clamp(options.deflate_level, 1, 9)) == Z_OK &&
        bound < raw.size()) {
      stored.resize(bound);
      flags |= kFlagDeflate;
    }
  }
  if (!(flags & kFlagDeflate)) stored = raw;

  EncodedTile out;
  out.bytes.reserve(kTileHeaderBytes + stored.size() + kCrcBytes);
  ByteWriter w(out.bytes);
  w.bytes(kTileMagic, 4);
  w.u16(kTileFormatVersion);
  w.u16(flags);
  w.i32(tile.id().x);
  w.i32(tile.id().y);
  w.u32(static_cast<uint32_t>(size));
  w.u32(total);
  w.f64(base);
  w.f64(quantum);
  w.u32(static_cast<uint32_t>(raw.size()));
  w.u32(static_cast<uint32_t>(stored.size()));
  w.bytes(stored.data(), stored.size());
  w.u32(crc32Of(out.bytes.data(), out.bytes.size()));

  // The manifest entry describes what a reader will get: decode what was just written.
  auto decoded = decodeTile(out.bytes.data(), out.bytes.size(), tileFileName(tile.id()));
  if (!decoded) return R::failure("encoder self-check failed: " + decoded.error());
  out.info = summarizeTile(**decoded);
  out.info.file_name = tileFileName(tile.id());
  out.info.byte_size = out.bytes.size();
  out.info.crc32 = crc32Of(out.bytes.data(), out.bytes.size() - kCrcBytes);
  return out;
}

Result<std::shared_ptr<GmmTile>> decodeTile(const uint8_t* data, size_t size,
                                            const std::string& source, const TileId* expected_id,
                                            int32_t expected_size_cells) {
  using R = Result<std::shared_ptr<GmmTile>>;
  auto fail = [&](const std::string& what) {
    return R::failure("tile file '" + source + "': " + what);
  };
  ByteReader r(data, size);
  const std::string start = map_format::readFileStart(r, data, size, kTileMagic, "GMM tile file",
                                                      kTileFormatVersion, kTileFormatVersion);
  if (!start.empty()) return fail(start);
  if (size < kTileHeaderBytes + kCrcBytes) {
    return fail("truncated: " + std::to_string(size) + " bytes, a version-1 tile has at least " +
                std::to_string(kTileHeaderBytes + kCrcBytes));
  }
  const uint16_t flags = r.u16("flags");
  const TileId id{r.i32("tile x"), r.i32("tile y")};
  const uint32_t tile_size = r.u32("tile size");
  const uint32_t total = r.u32("component count");
  const double base = r.f64("base height");
  const double quantum = r.f64("mean quantum");
  const uint32_t raw_bytes = r.u32("raw payload size");
  const uint32_t stored_bytes = r.u32("stored payload size");
  if (static_cast<uint64_t>(stored_bytes) + kTileHeaderBytes + kCrcBytes != size) {
    return fail("inconsistent sizes: header declares a " + std::to_string(stored_bytes) +
                "-byte payload, i.e. a file of " +
                std::to_string(uint64_t{stored_bytes} + kTileHeaderBytes + kCrcBytes) +
                " bytes, but the file has " + std::to_string(size) + " (truncated or extended)");
  }
  const uint32_t stored_crc = static_cast<uint32_t>(data[size - 4]) | (data[size - 3] << 8) |
                              (data[size - 2] << 16) |
                              (static_cast<uint32_t>(data[size - 1]) << 24);
  const uint32_t crc = crc32Of(data, size - kCrcBytes);
  if (crc != stored_crc) {
    std::ostringstream s;
    s << "CRC-32 mismatch (stored 0x" << std::hex << stored_crc << ", computed 0x" << crc
      << "): the file is corrupted";
    return fail(s.str());
  }
  if (flags & ~kFlagDeflate) return fail("unknown flags 0x" + std::to_string(flags));
  if (tile_size < 8 || tile_size > 4096) {
    return fail("tile size " + std::to_string(tile_size) + " not in [8, 4096]");
  }
  if (expected_id && id != *expected_id) {
    return fail("holds tile (" + std::to_string(id.x) + ", " + std::to_string(id.y) +
                "), expected (" + std::to_string(expected_id->x) + ", " +
                std::to_string(expected_id->y) + ")");
  }
  if (expected_size_cells > 0 && static_cast<int32_t>(tile_size) != expected_size_cells) {
    return fail("tile size " + std::to_string(tile_size) + " cells, the map uses " +
                std::to_string(expected_size_cells));
  }
  if (!std::isfinite(base) || !(quantum > 0.0 && quantum < 1e9)) {
    return fail("invalid base height or mean quantum");
  }
  const size_t n_cells = static_cast<size_t>(tile_size) * tile_size;
  const size_t k_bytes = (n_cells + 3) / 4;
  const uint64_t max_raw = k_bytes + uint64_t{n_cells} * kMaxMixtureComponents * 6;
  if (raw_bytes < k_bytes || raw_bytes > max_raw) {
    return fail("inconsistent sizes: raw payload of " + std::to_string(raw_bytes) +
                " bytes is impossible for " + std::to_string(tile_size) + "^2 cells");
  }
  const uint8_t* payload = data + kTileHeaderBytes;
  std::vector<uint8_t> raw;
  if (flags & kFlagDeflate) {
    raw.resize(raw_bytes);
    uLongf out_len = raw_bytes;
    const int z = uncompress(raw.data(), &out_len, payload, stored_bytes);
    if (z != Z_OK || out_len != raw_bytes) {
      return fail("deflated payload does not inflate to the declared " + std::to_string(raw_bytes) +
                  " bytes (zlib status " + std::to_string(z) + ")");
    }
  } else {
    if (stored_bytes != raw_bytes) return fail("inconsistent sizes: stored != raw without deflate");
    raw.assign(payload, payload + stored_bytes);
  }

  auto tile = std::make_shared<GmmTile>(id, static_cast<int32_t>(tile_size));
  std::vector<uint8_t> k_of(n_cells);
  std::array<size_t, kMaxMixtureComponents> slot{}, wslot{};
  for (size_t i = 0; i < n_cells; ++i) {
    k_of[i] = (raw[i / 4] >> (2 * (i % 4))) & 3;
    for (int j = 0; j < k_of[i]; ++j) {
      ++slot[j];
      if (k_of[i] >= 2) ++wslot[j];
    }
  }
  size_t comps = 0, weight_codes = 0;
  for (int j = 0; j < kMaxMixtureComponents; ++j) {
    comps += slot[j];
    weight_codes += wslot[j];
  }
  if (comps != total) {
    return fail("inconsistent sizes: header counts " + std::to_string(total) +
                " components, the cell table " + std::to_string(comps));
  }
  if (raw_bytes != k_bytes + 4 * comps + 2 * weight_codes) {
    return fail("inconsistent sizes: raw payload of " + std::to_string(raw_bytes) +
                " bytes, the cell table needs " +
                std::to_string(k_bytes + 4 * comps + 2 * weight_codes));
  }
  // Planes: mean slots 0..2, sigma slots 0..2, weight slots 0..2.
  size_t pos = k_bytes;
  std::array<std::vector<uint16_t>, 3 * kSlots> planes;
  for (int field = 0; field < 3; ++field) {
    for (int j = 0; j < kMaxMixtureComponents; ++j) {
      const size_t n = field == 2 ? wslot[j] : slot[j];
      auto& v = planes[field * kSlots + j];
      v = getPlanes(raw.data() + pos, n);
      pos += 2 * n;
      if (field < 2) {
        uint16_t acc = 0;
        for (auto& c : v) c = acc = static_cast<uint16_t>(acc + c);
      }
    }
  }
  std::array<size_t, 3 * kSlots> next{};
  auto& out = tile->cells();
  for (size_t i = 0; i < n_cells; ++i) {
    const int k = k_of[i];
    double wsum = 0.0;
    std::array<double, kMaxMixtureComponents> w{};
    for (int j = 0; j < k; ++j) {
      w[j] = k >= 2 ? weightValue(planes[2 * kSlots + j][next[2 * kSlots + j]++]) : 1.0;
      wsum += w[j];
    }
    for (int j = 0; j < k; ++j) {
      GaussianComponent c;
      c.mean_m = static_cast<float>(base + quantum * planes[j][next[j]++]);
      c.sigma_m = static_cast<float>(sigmaValue(planes[kSlots + j][next[kSlots + j]++]));
      c.weight = static_cast<float>(w[j] / wsum);
      const std::string bad = checkComponentBounds(c);
      if (!bad.empty()) {
        return fail("invalid value in " + cellName(*tile, i) + ", component " + std::to_string(j) +
                    ": " + bad);
      }
      out[i].add(c);
    }
  }
  return R(std::move(tile));
}

}  // namespace gmm_localization
