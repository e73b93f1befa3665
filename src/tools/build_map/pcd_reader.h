#pragma once
// A PCD (point cloud data, v0.5-0.7) reader of our own, for build_map: every header line and
// every size is checked against the file before a point is decoded, so a truncated, garbled or
// lying file is answered with an error naming the file and the problem, never with a crash, an
// exception or made-up points. No PCL.
//
// Format (PCL's): text header lines (comments start with '#')
//   VERSION 0.7 | FIELDS names | SIZE bytes | TYPE F|I|U | COUNT n | WIDTH w | HEIGHT h |
//   VIEWPOINT tx ty tz qw qx qy qz | POINTS w*h | DATA ascii|binary|binary_compressed
// then the data: ascii = one line of numbers per point; binary = packed little-endian records
// of sum(SIZE * COUNT) bytes, point after point; binary_compressed = [compressed size u32]
// [uncompressed size u32][LZF data] whose decompressed bytes hold the fields column-wise (every
// point's first field, then every point's second field, ...).
// Defaults as in PCL: no VERSION accepted, COUNT 1, HEIGHT 1, POINTS = WIDTH * HEIGHT,
// VIEWPOINT identity (read and reported, never applied, as in PCL).
// x, y and z are required (COUNT 1, any numeric type: F4, F8, I1-I8, U1-U8) and are decoded in
// double. The host must be little-endian (as PCL's writer on x86 and ARM).

#include <array>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "gmm_localization/core/common/result.h"

namespace gmm_localization {
namespace tools {

enum class PcdData { kAscii, kBinary, kBinaryCompressed };

struct PcdField {
  std::string name;
  int size = 4;       ///< bytes per element: 1, 2, 4 or 8 (F: 4 or 8)
  char type = 'F';    ///< F float, I signed integer, U unsigned integer
  int count = 1;      ///< elements per point
  size_t offset = 0;  ///< byte offset in a packed record (binary)
  size_t bytes() const { return static_cast<size_t>(size) * count; }
  /// "F8", "U1", ...
  std::string typeName() const { return std::string(1, type) + std::to_string(size); }
};

struct PcdHeader {
  std::string version;  ///< as written; empty when the header has no VERSION line
  std::vector<PcdField> fields;
  uint64_t width = 0, height = 1, points = 0;
  std::array<double, 7> viewpoint{{0, 0, 0, 1, 0, 0, 0}};  ///< tx ty tz qw qx qy qz
  PcdData data = PcdData::kAscii;
  size_t data_offset = 0;      ///< bytes from the start of the file to the data
  size_t point_bytes = 0;      ///< sum of SIZE * COUNT
  int x = -1, y = -1, z = -1;  ///< field indices
  int intensity = -1;          ///< "intensity", "i" or "reflectivity" (COUNT 1), -1: none
  size_t tokens = 0;           ///< numbers per ascii line: sum of COUNT

  bool viewpointIsIdentity() const;
  /// "x y z F8, intensity F4, 2 more fields"
  std::string describeFields() const;
  static const char* dataName(PcdData d);
};

/// A token for an error message: at most 40 characters, control bytes shown as '?', quoted.
std::string quotedPcdToken(const std::string& s);

/// Largest header accepted (bytes up to and including the DATA line).
constexpr size_t kMaxPcdHeaderBytes = size_t{1} << 20;

/// Parses and checks a header from the first bytes of a file (`text` may continue past the DATA
/// line; pcd_header.cpp). Fails with the line number and the problem: no DATA line, an unknown or
/// repeated keyword, a bad number, counts that disagree with FIELDS, a bad SIZE/TYPE pair, POINTS
/// != WIDTH * HEIGHT, x/y/z missing, repeated or with COUNT != 1, sizes that overflow.
Result<PcdHeader> parsePcdHeader(const std::string& text);

/// One PCD file, read point by point in batches. open() checks everything that can be checked
/// before decoding: the header; for binary, that the file holds POINTS * point size bytes; for
/// binary_compressed, both sizes (the uncompressed one must be POINTS * point size and
/// achievable by LZF, the compressed one must fit in the file) and the whole LZF stream
/// (decompressed into memory, kept for reading); for ascii, every line is parsed once (count of
/// numbers, each a number, POINTS lines). Every error names the file.
class PcdFileReader {
 public:
  static Result<std::unique_ptr<PcdFileReader>> open(const std::string& path);
  ~PcdFileReader();
  PcdFileReader(const PcdFileReader&) = delete;
  PcdFileReader& operator=(const PcdFileReader&) = delete;

  const std::string& path() const { return path_; }
  const PcdHeader& header() const { return header_; }
  /// Oddities found by open() that do not stop the read (data after the last point, a
  /// VIEWPOINT that is not identity), one sentence each, naming the file.
  const std::vector<std::string>& notes() const { return notes_; }

  /// Appends up to max_points points (x, y, z as stored, in double) to `xyz`; returns how many,
  /// 0 at the end. Fails (naming the file) only when the file changed since open(). When
  /// `intensity` is given and the file has an intensity field (header().intensity), one value
  /// per point is appended to it too (as stored, narrowed to float).
  Result<size_t> read(size_t max_points, std::vector<Eigen::Vector3d>& xyz,
                      std::vector<float>* intensity = nullptr);

 private:
  PcdFileReader() = default;
  Status checkBinary(uint64_t file_bytes);
  Status loadCompressed(uint64_t file_bytes);
  Status scanAscii();
  Result<size_t> readAscii(size_t n, std::vector<Eigen::Vector3d>& xyz, bool keep,
                           std::vector<float>* intensity);
  std::string fail(const std::string& why) const;

  std::string path_;
  PcdHeader header_;
  std::vector<std::string> notes_;
  std::FILE* file_ = nullptr;
  uint64_t next_ = 0;            ///< next point to read
  uint64_t header_lines_ = 0;    ///< lines before the data
  uint64_t ascii_line_ = 0;      ///< file line number of the last ascii line read
  std::vector<uint8_t> buffer_;  ///< binary: one batch; compressed: the whole data
  char* line_ = nullptr;         ///< ascii line buffer (getline's)
  size_t line_capacity_ = 0;
  std::array<size_t, 4> token_{};  ///< ascii: token index of x, y, z, intensity (when present)
};

}  // namespace tools
}  // namespace gmm_localization
