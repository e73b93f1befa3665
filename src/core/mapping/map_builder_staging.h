#pragma once
// Private to the map builder: the staging directory of a build, the lock on the output
// directory, the swap of a finished map into place and the recovery of killed builds (the
// design is described in map_builder.h, "Replacing a map").

#include <cstddef>
#include <cstdint>
#include <string>

#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/map/map_format.h"

namespace gmm_localization {
namespace map_builder {

constexpr const char* kStagingPrefix = ".gmm_build.";          ///< + "<pid>.<n>", inside the output
constexpr const char* kJournalFileName = "journal";            ///< in the staging directory
constexpr const char* kJournalHeader = "gmm_build journal 1";  ///< first line of a journal
constexpr const char* kStagedManifestName = "manifest.next";   ///< never "manifest.gmm" in staging

/// An exclusive flock(2) on a directory, held until release() or destruction. Only one map
/// builder at a time may use an output directory; the lock also tells that every staging
/// directory found there belongs to a build that is gone.
class DirectoryLock {
 public:
  enum class Outcome { kHeld, kBusy, kUnsupported };
  DirectoryLock() = default;
  ~DirectoryLock() { release(); }
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;

  /// Tries to lock `dir` without waiting. kBusy: another builder (in any process) holds it;
  /// kUnsupported: the file system refuses flock on a directory (nothing is held).
  Outcome tryLock(const std::string& dir);
  bool held() const { return fd_ >= 0; }
  void release();

 private:
  int fd_ = -1;
};

/// Creates a fresh, empty `<dir>/.gmm_build.<pid>.<n>` and returns its path.
Result<std::string> createStagingDirectory(const std::string& dir);

/// Removes the staging directories left in `dir` by builds that are gone, after undoing what
/// their swap had already moved into `dir` (their journal). `exclusive`: the caller holds the
/// directory's lock, so every staging directory is a leftover; otherwise only those whose
/// process no longer exists are. Returns how many were removed.
size_t recoverStagingDirectories(const std::string& dir, bool exclusive);

/// The swap. `manifest` lists the tiles staged in `staging` under their file_name. Picks the
/// generation tag (see taggedTileName) so that no new file name is one the current map in `dir`
/// uses, writes the journal, moves the tiles into `dir`, then renames the new manifest over
/// `dir/manifest.gmm` (the commit) and finally removes the old map's tile files. Fails, with
/// `dir` as it was, when a step before the commit fails, or when `dir` has gained a map since
/// create() and `overwrite` is false. Returns the new manifest's size [bytes].
Result<uint64_t> commitStagedMap(const std::string& dir, const std::string& staging,
                                 MapManifest manifest, bool overwrite);

/// "tile_3_-7.gmt" with tag "g1" -> "tile_3_-7.g1.gmt" (before the last '.'); "" -> unchanged.
std::string taggedTileName(const std::string& file_name, const std::string& tag);

/// fsync(2) of a directory, so renames in it are durable. Best effort: some file systems
/// refuse it; returns false then.
bool syncDirectory(const std::string& dir);

}  // namespace map_builder
}  // namespace gmm_localization
