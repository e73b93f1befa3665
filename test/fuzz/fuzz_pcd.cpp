// Fuzz target: the PCD reader of build_map (src/tools/build_map/pcd_reader.h: parsePcdHeader,
// PcdFileReader with its ascii, binary and binary_compressed/LZF paths). The input is a whole
// .pcd file (an in-memory file). The reader's contract: open() checks everything that can be
// checked before decoding, so once open() has accepted a file, read() delivers exactly POINTS
// points (and as many intensities when the file has an intensity field) and fails only when the
// file changes (it does not change here).
#include <cstdint>
#include <string>
#include <vector>

#include "build_map/pcd_reader.h"
#include "fuzz_check.h"
#include "fuzz_file.h"

using namespace gmm_localization;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static fuzz::MemFile file("fuzz.pcd");
  const std::string text(reinterpret_cast<const char*>(data),
                         std::min(size, tools::kMaxPcdHeaderBytes));
  auto header = tools::parsePcdHeader(text);
  if (header) {
    FUZZ_CHECK(header->x >= 0 && header->y >= 0 && header->z >= 0, "no x, y or z");
    FUZZ_CHECK(header->points == header->width * header->height, "POINTS != WIDTH x HEIGHT");
  }

  auto reader = tools::PcdFileReader::open(file.set(data, size));
  if (!reader) return 0;
  const uint64_t points = (*reader)->header().points;
  uint64_t total = 0;
  const bool has_intensity = (*reader)->header().intensity >= 0;
  std::vector<Eigen::Vector3d> xyz;
  std::vector<float> intensity;
  for (;;) {
    xyz.clear();
    intensity.clear();
    auto n = (*reader)->read(4096, xyz, &intensity);
    FUZZ_CHECK(n.ok(), "read() failed after open() accepted the file: %s", n.error().c_str());
    FUZZ_CHECK(*n == xyz.size(), "read() returned %zu, delivered %zu", *n, xyz.size());
    FUZZ_CHECK(intensity.size() == (has_intensity ? xyz.size() : 0), "%zu intensities for %zu",
               intensity.size(), xyz.size());
    if (*n == 0) break;
    total += *n;
    FUZZ_CHECK(total <= points, "more points than POINTS");
  }
  FUZZ_CHECK(total == points, "%llu points of POINTS %llu", (unsigned long long)total,
             (unsigned long long)points);
  return 0;
}
