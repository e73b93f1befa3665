// Fuzz target: the KITTI reader (core/mapping/kitti_source.h) that build_map and kitti_check
// run on scan directories. The first input byte selects what the rest is:
//   0, 1, 2  a scan file (readKittiScan with KittiFields kAuto, kXyz, kXyzi)
//   3        a poses file, KITTI 3x4 or graph lines (readKittiPoses)
//   4        a calib.txt (readKittiCalibTr)
//   5        a --scans index list (parseIndexList)
//   6        a scan directory: poses.txt up to the first NUL byte, then 000000.bin
//            (KittiScanSource::open, then next() until the end)
// Contracts checked: a scan has one point per record; every pose (and Tr) read is a rigid
// transform - finite, with an orthonormal rotation; an index list holds indices >= 0.
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "fuzz_check.h"
#include "fuzz_file.h"
#include "gmm_localization/core/mapping/kitti_source.h"

namespace {

using namespace gmm_localization;

void checkRigid(const Eigen::Isometry3d& t, const char* what) {
  FUZZ_CHECK(t.matrix().allFinite(), "%s is not finite", what);
  const double e = (t.linear().transpose() * t.linear() - Eigen::Matrix3d::Identity()).norm();
  FUZZ_CHECK(e < 1e-6, "%s has a rotation that is not orthonormal (error %g)", what, e);
}

/// A scan directory of our own, rewritten for every input and removed at exit.
class ScanDirectory {
 public:
  ScanDirectory() {
    const char* tmp = std::getenv("TMPDIR");
    path_ = std::string(tmp && *tmp ? tmp : "/tmp") + "/gmm_fuzz_kitti.XXXXXX";
    if (!mkdtemp(&path_[0])) std::abort();
  }
  ~ScanDirectory() {
    ::unlink((path_ + "/poses.txt").c_str());
    ::unlink((path_ + "/000000.bin").c_str());
    ::rmdir(path_.c_str());
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

void writeFile(const std::string& path, const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static fuzz::MemFile file("fuzz_kitti");
  const uint8_t mode = data[0] % 7;
  ++data;
  --size;
  switch (mode) {
    case 0:
    case 1:
    case 2: {
      const KittiFields fields = mode == 0   ? KittiFields::kAuto
                                 : mode == 1 ? KittiFields::kXyz
                                             : KittiFields::kXyzi;
      auto scan = readKittiScan(file.set(data, size), fields);
      if (scan) {
        const size_t stride = fields == KittiFields::kXyz    ? 12
                              : fields == KittiFields::kXyzi ? 16
                                                             : 0;
        FUZZ_CHECK(stride == 0 ? (scan->size() * 12 == size || scan->size() * 16 == size)
                               : scan->size() * stride == size,
                   "%zu points from %zu bytes", scan->size(), size);
      }
      break;
    }
    case 3: {
      auto poses = readKittiPoses(file.set(data, size));
      if (poses) {
        for (const auto& kv : *poses) {
          FUZZ_CHECK(kv.first >= 0, "negative scan index");
          checkRigid(kv.second, "a pose");
        }
      }
      break;
    }
    case 4: {
      auto tr = readKittiCalibTr(file.set(data, size));
      if (tr) checkRigid(*tr, "Tr");
      break;
    }
    case 5: {
      auto list = parseIndexList(std::string(reinterpret_cast<const char*>(data), size));
      if (list) {
        for (int i : *list) FUZZ_CHECK(i >= 0, "negative index %d", i);
      }
      break;
    }
    default: {
      const uint8_t* nul = static_cast<const uint8_t*>(std::memchr(data, 0, size));
      const size_t text = nul ? static_cast<size_t>(nul - data) : size;
      static const ScanDirectory directory;
      const std::string& dir = directory.path();
      writeFile(dir + "/poses.txt", data, text);
      const size_t bin = nul ? text + 1 : size;
      writeFile(dir + "/000000.bin", data + bin, size - bin);
      KittiSourceOptions options;
      options.scans_directory = dir;
      auto source = KittiScanSource::open(options);
      if (!source) break;
      for (const auto& scan : (*source)->scans()) checkRigid(scan.map_T_sensor, "a scan pose");
      PointBatch batch;
      for (int i = 0; i < 4; ++i) {
        auto more = (*source)->next(batch);
        if (!more || !*more) break;
      }
      break;
    }
  }
  return 0;
}
