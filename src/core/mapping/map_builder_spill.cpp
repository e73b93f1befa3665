#include "map_builder_spill.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace gmm_localization {
namespace map_builder {
namespace {
// A spill file is compacted (read, merged, rewritten) when it has grown to this many bytes and
// to twice its size after the previous compaction, so repeated passes over a tile cannot make
// its file (and pass 2's memory) grow without bound.
constexpr uint64_t kCompactMinBytes = uint64_t{64} << 20;

/// (ey, ex, zbin) packed so that one integer comparison orders records.
inline uint64_t sortKey(const SpillRecord& r) {
  return (uint64_t{r.ey} << 48) | (uint64_t{r.ex} << 32) |
         (static_cast<uint32_t>(r.zbin) ^ 0x80000000u);
}
}  // namespace

/// LSD radix sort on sortKey, one byte per pass; bytes equal in every key are skipped (the z
/// bins of one buffer span a few thousand values, so typically 6 of 8 passes run). Stable.
void radixSort(std::vector<SpillRecord>& r) {
  std::vector<uint64_t> keys(r.size());
  std::array<std::array<size_t, 257>, 8> count{};
  for (size_t i = 0; i < r.size(); ++i) {
    keys[i] = sortKey(r[i]);
    for (int b = 0; b < 8; ++b) ++count[b][((keys[i] >> (8 * b)) & 0xff) + 1];
  }
  std::vector<SpillRecord> tmp(r.size());
  std::vector<uint64_t> tmp_keys(r.size());
  for (int b = 0; b < 8; ++b) {
    auto& c = count[b];
    if (*std::max_element(c.begin(), c.end()) == r.size()) continue;  // byte is constant
    for (int d = 0; d < 256; ++d) c[d + 1] += c[d];
    for (size_t i = 0; i < r.size(); ++i) {
      const size_t to = c[(keys[i] >> (8 * b)) & 0xff]++;
      tmp[to] = r[i];
      tmp_keys[to] = keys[i];
    }
    r.swap(tmp);
    keys.swap(tmp_keys);
  }
}

void sortAndMerge(std::vector<SpillRecord>& r) {
  if (r.size() > 1024) {
    radixSort(r);
  } else {
    std::sort(r.begin(), r.end(),
              [](const SpillRecord& a, const SpillRecord& b) { return sortKey(a) < sortKey(b); });
  }
  size_t out = 0;
  for (size_t i = 0; i < r.size(); ++i) {
    if (out > 0 && r[out - 1].ey == r[i].ey && r[out - 1].ex == r[i].ex &&
        r[out - 1].zbin == r[i].zbin) {
      const uint64_t sum = uint64_t{r[out - 1].count} + r[i].count;
      r[out - 1].count = static_cast<uint32_t>(std::min<uint64_t>(sum, UINT32_MAX));
    } else {
      r[out++] = r[i];
    }
  }
  r.resize(out);
}

SpillStore::SpillStore(std::string directory, size_t buffer_bytes) : dir_(std::move(directory)) {
  max_buffered_records_ = std::max<size_t>(buffer_bytes / sizeof(SpillRecord), 1024);
  per_tile_records_ = std::clamp<size_t>(max_buffered_records_ / 8, 1024, size_t{1} << 17);
}

std::string SpillStore::path(const TileId& t) const {
  return dir_ + "/t_" + std::to_string(t.x) + "_" + std::to_string(t.y) + ".spill";
}

std::vector<SpillRecord>& SpillStore::buffer(const TileId& tile) { return buffers_[tile]; }

Status SpillStore::afterAppend(const TileId& tile, std::vector<SpillRecord>& buffer,
                               size_t appended) {
  buffered_ += appended;
  if (buffer.size() >= per_tile_records_) {
    buffered_ -= buffer.size();
    Status s = flush(tile, buffer);
    if (!s) return s;
  }
  if (buffered_ >= max_buffered_records_) return flushAll();
  return Status::success();
}

Status SpillStore::flushAll() {
  for (auto& [tile, records] : buffers_) {
    Status s = flush(tile, records);
    if (!s) return s;
  }
  buffered_ = 0;
  return Status::success();
}

Status SpillStore::append(const TileId& tile, const std::vector<SpillRecord>& records,
                          bool truncate) {
  const std::string p = path(tile);
  FILE* f = std::fopen(p.c_str(), truncate ? "wb" : "ab");
  if (!f) return Status::failure("spill file '" + p + "': cannot open: " + std::strerror(errno));
  errno = 0;
  const size_t n = std::fwrite(records.data(), sizeof(SpillRecord), records.size(), f);
  int e = errno;
  // A full disk may show only when the buffered tail is written out, by fclose.
  errno = 0;
  const bool closed = std::fclose(f) == 0;
  if (e == 0) e = errno;
  if (n != records.size() || !closed) {
    return Status::failure("spill file '" + p +
                           "': write failed: " + (e != 0 ? std::strerror(e) : "short write"));
  }
  const uint64_t bytes = uint64_t{records.size()} * sizeof(SpillRecord);
  bytes_written_ += bytes;
  file_bytes_[tile] = (truncate ? 0 : file_bytes_[tile]) + bytes;
  return Status::success();
}

Status SpillStore::flush(const TileId& tile, std::vector<SpillRecord>& records) {
  if (records.empty()) return Status::success();
  sortAndMerge(records);
  Status s = append(tile, records, false);
  records.clear();
  records.shrink_to_fit();
  if (!s) return s;
  const uint64_t size = file_bytes_[tile];
  if (size >= kCompactMinBytes && size >= 2 * compacted_bytes_[tile]) {
    auto all = read(tile);
    if (!all) return Status::failure(all.error());
    s = append(tile, *all, true);
    if (!s) return s;
    compacted_bytes_[tile] = file_bytes_[tile];
  }
  return Status::success();
}

std::vector<TileId> SpillStore::tiles() const {
  std::vector<TileId> out;
  for (const auto& entry : file_bytes_) out.push_back(entry.first);
  std::sort(out.begin(), out.end());
  return out;
}

uint64_t SpillStore::fileBytes(const TileId& tile) const {
  auto it = file_bytes_.find(tile);
  return it == file_bytes_.end() ? 0 : it->second;
}

Result<std::vector<SpillRecord>> SpillStore::read(const TileId& tile) const {
  using R = Result<std::vector<SpillRecord>>;
  const std::string p = path(tile);
  const uint64_t bytes = fileBytes(tile);
  std::vector<SpillRecord> records(bytes / sizeof(SpillRecord));
  FILE* f = std::fopen(p.c_str(), "rb");
  if (!f) return R::failure("spill file '" + p + "': cannot open: " + std::strerror(errno));
  const size_t n = std::fread(records.data(), sizeof(SpillRecord), records.size(), f);
  const bool at_end = std::fgetc(f) == EOF;
  std::fclose(f);
  if (n != records.size() || !at_end) {
    return R::failure("spill file '" + p + "': expected " + std::to_string(bytes) +
                      " bytes, read a different amount");
  }
  sortAndMerge(records);
  return records;
}

void SpillStore::remove(const TileId& tile) const { ::unlink(path(tile).c_str()); }

}  // namespace map_builder
}  // namespace gmm_localization
