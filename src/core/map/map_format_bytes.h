#pragma once
// Private to the map format: explicit little-endian byte writing and bounds-checked reading.
// Values are assembled byte by byte, so the host's endianness and struct layout never matter.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "gmm_localization/core/map/map_format.h"

namespace gmm_localization {
namespace map_format {

class ByteWriter {
 public:
  explicit ByteWriter(std::vector<uint8_t>& out) : out_(out) {}
  void u8(uint8_t v) { out_.push_back(v); }
  void u16(uint16_t v) {
    for (int i = 0; i < 2; ++i) out_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  void u32(uint32_t v) {
    for (int i = 0; i < 4; ++i) out_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  void u64(uint64_t v) {
    for (int i = 0; i < 8; ++i) out_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  void i32(int32_t v) { u32(static_cast<uint32_t>(v)); }
  void f32(float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);  // a scalar's bit pattern, not a struct
    u32(bits);
  }
  void f64(double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    u64(bits);
  }
  void str(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    out_.insert(out_.end(), s.begin(), s.end());
  }
  void bytes(const uint8_t* p, size_t n) {
    if (n == 0) return;
    const size_t at = out_.size();
    out_.resize(at + n);
    std::memcpy(out_.data() + at, p, n);
  }
  size_t size() const { return out_.size(); }

 private:
  std::vector<uint8_t>& out_;
};

/// Reads with bounds checks. After the first overrun every read returns 0 and ok() is false;
/// error() then names the field that did not fit and the offset.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool ok() const { return ok_; }
  const std::string& error() const { return error_; }
  size_t offset() const { return pos_; }
  size_t remaining() const { return size_ - pos_; }

  uint8_t u8(const char* what) { return static_cast<uint8_t>(take(1, what)); }
  uint16_t u16(const char* what) { return static_cast<uint16_t>(take(2, what)); }
  uint32_t u32(const char* what) { return static_cast<uint32_t>(take(4, what)); }
  uint64_t u64(const char* what) { return take(8, what); }
  int32_t i32(const char* what) { return static_cast<int32_t>(u32(what)); }
  float f32(const char* what) {
    const uint32_t bits = u32(what);
    float v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  double f64(const char* what) {
    const uint64_t bits = u64(what);
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  /// A u32-length string; fails when longer than max_length or than the remaining bytes.
  std::string str(const char* what, uint32_t max_length) {
    const uint32_t n = u32(what);
    if (!ok_) return {};
    if (n > max_length || n > remaining()) {
      fail(what, n);
      return {};
    }
    std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return s;
  }

 private:
  uint64_t take(size_t n, const char* what) {
    if (!ok_) return 0;
    if (n > remaining()) {
      fail(what, n);
      return 0;
    }
    uint64_t v = 0;
    for (size_t i = 0; i < n; ++i) v |= static_cast<uint64_t>(data_[pos_ + i]) << (8 * i);
    pos_ += n;
    return v;
  }
  void fail(const char* what, uint64_t n) {
    ok_ = false;
    error_ = std::string("truncated: ") + what + " needs " + std::to_string(n) +
             " bytes at offset " + std::to_string(pos_) + " of " + std::to_string(size_);
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  bool ok_ = true;
  std::string error_;
};

/// The start of every map file: 4 magic bytes, then the format version (u16). Reads both with
/// r, which must stand at the start of data[0, size); empty when they are `magic` and a version
/// in [min_version, max_version] (stored in *version), else why not (`kind` names the file
/// expected: "GMM tile file").
inline std::string readFileStart(ByteReader& r, const uint8_t* data, size_t size,
                                 const uint8_t (&magic)[4], const char* kind, uint16_t min_version,
                                 uint16_t max_version, uint16_t* version = nullptr) {
  if (size < 4) return "truncated: " + std::to_string(size) + " bytes, no room for the magic";
  if (!std::equal(data, data + 4, magic)) return std::string("wrong magic (not a ") + kind + ")";
  r.u32("magic");
  const uint16_t v = r.u16("format version");
  if (!r.ok()) return r.error();
  if (v < min_version || v > max_version) {
    const std::string reads = min_version == max_version ? std::to_string(max_version)
                                                         : std::to_string(min_version) + " to " +
                                                               std::to_string(max_version);
    return "unsupported format version " + std::to_string(v) + " (this build reads " + reads + ")";
  }
  if (version != nullptr) *version = v;
  return {};
}

}  // namespace map_format
}  // namespace gmm_localization
