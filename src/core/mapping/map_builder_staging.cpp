// Map builder: staging directory, output directory lock, swap of a finished map into place and
// recovery of the leftovers of killed builds.
#include "map_builder_staging.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>
#include <sstream>
#include <vector>

#include "gmm_localization/core/common/errno_text.h"

namespace gmm_localization {
namespace map_builder {
namespace {

namespace fs = std::filesystem;

bool pathExists(const std::string& path) {
  struct stat st;
  return ::lstat(path.c_str(), &st) == 0;
}

/// The pid in ".gmm_build.<pid>.<n>", 0 when the name has none.
long stagingPid(const std::string& name) {
  const size_t prefix = std::strlen(kStagingPrefix);
  if (name.compare(0, prefix, kStagingPrefix) != 0) return 0;
  char* end = nullptr;
  const long pid = std::strtol(name.c_str() + prefix, &end, 10);
  return end != nullptr && *end == '.' ? pid : 0;
}

bool processGone(long pid) {
  return pid > 0 && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

/// The map currently in a directory: whether it has a manifest, whether that manifest reads,
/// and the tile file names it references.
struct CurrentMap {
  bool exists = false;
  bool readable = false;
  std::set<std::string> files;
};

CurrentMap currentMap(const std::string& dir) {
  CurrentMap c;
  c.exists = pathExists(dir + "/" + kManifestFileName);
  if (!c.exists) return c;
  auto manifest = readManifest(dir);
  if (!manifest) return c;
  c.readable = true;
  for (const TileInfo& t : manifest->tiles) c.files.insert(t.file_name);
  return c;
}

bool plainFileName(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name != kManifestFileName &&
         name.find('/') == std::string::npos && name.find('\n') == std::string::npos &&
         name.find('\0') == std::string::npos;
}

/// Deletes every file of a dead build's journal that the map now in `dir` does not reference.
/// Does nothing when `dir` has a manifest that cannot be read (no telling which files are its).
void undoJournal(const std::string& dir, const std::string& journal_path) {
  auto bytes = readFileBytes(journal_path, uint64_t{64} << 20);
  if (!bytes) return;  // killed before step 2: nothing reached `dir`
  std::istringstream in(std::string(bytes->begin(), bytes->end()));
  std::string line;
  if (!std::getline(in, line) || line != kJournalHeader) return;
  const CurrentMap current = currentMap(dir);
  if (current.exists && !current.readable) return;
  bool removed = false;
  while (std::getline(in, line)) {
    if (!plainFileName(line) || current.files.count(line) > 0) continue;
    removed |= ::unlink((dir + "/" + line).c_str()) == 0;
  }
  if (removed) syncDirectory(dir);
}

}  // namespace

DirectoryLock::Outcome DirectoryLock::tryLock(const std::string& dir) {
  release();
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return Outcome::kUnsupported;
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0) {
    fd_ = fd;
    return Outcome::kHeld;
  }
  const int e = errno;
  ::close(fd);
  return e == EWOULDBLOCK ? Outcome::kBusy : Outcome::kUnsupported;
}

void DirectoryLock::release() {
  if (fd_ >= 0) ::close(fd_);  // closing the last descriptor releases the flock
  fd_ = -1;
}

bool syncDirectory(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

std::string taggedTileName(const std::string& file_name, const std::string& tag) {
  if (tag.empty()) return file_name;
  const size_t dot = file_name.find_last_of('.');
  if (dot == std::string::npos || dot == 0) return file_name + "." + tag;
  return file_name.substr(0, dot) + "." + tag + file_name.substr(dot);
}

Result<std::string> createStagingDirectory(const std::string& dir) {
  static std::atomic<uint64_t> counter{0};
  for (int attempt = 0; attempt < 1000; ++attempt) {
    const std::string path = dir + "/" + kStagingPrefix + std::to_string(::getpid()) + "." +
                             std::to_string(counter.fetch_add(1));
    if (::mkdir(path.c_str(), 0755) == 0) return path;
    if (errno != EEXIST) {
      return Result<std::string>::failure("cannot create staging directory '" + path +
                                          "': " + errnoText(errno));
    }
  }
  return Result<std::string>::failure("cannot create a staging directory in '" + dir +
                                      "': every name is taken");
}

size_t recoverStagingDirectories(const std::string& dir, bool exclusive) {
  std::vector<fs::path> found;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename();
    if (stagingPid(name) == 0) continue;
    std::error_code e2;
    if (entry.is_symlink(e2) || !entry.is_directory(e2)) continue;
    found.push_back(entry.path());
  }
  size_t removed = 0;
  for (const fs::path& p : found) {
    if (!exclusive && !processGone(stagingPid(p.filename()))) continue;
    undoJournal(dir, (p / kJournalFileName).string());
    fs::remove_all(p, ec);
    if (!ec) ++removed;
  }
  return removed;
}

Result<uint64_t> commitStagedMap(const std::string& dir, const std::string& staging,
                                 MapManifest manifest, bool overwrite) {
  using R = Result<uint64_t>;
  const CurrentMap current = currentMap(dir);
  if (current.exists && !overwrite) {
    return R::failure("output directory '" + dir + "' gained a map (" + kManifestFileName +
                      ") during the build; set overwrite (build_map: --overwrite)");
  }
  // 1. File names no file of the current map has. A manifest that cannot be read could name
  // anything in the directory: then no existing name is reused.
  std::set<std::string> taken = current.files;
  if (current.exists && !current.readable) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) taken.insert(e.path().filename());
  }
  std::string tag;
  for (int generation = 0;; ++generation) {
    if (generation > 1000) return R::failure("no free tile file names in '" + dir + "'");
    tag = generation == 0 ? std::string() : "g" + std::to_string(generation);
    bool clash = false;
    for (const TileInfo& t : manifest.tiles) {
      clash = clash || taken.count(taggedTileName(t.file_name, tag)) > 0;
    }
    if (!clash) break;
  }
  std::vector<std::string> staged, final_names;
  std::set<std::string> new_files;
  for (const TileInfo& t : manifest.tiles) {
    staged.push_back(t.file_name);
    final_names.push_back(taggedTileName(t.file_name, tag));
    new_files.insert(final_names.back());
  }

  // 2. The journal: every name a recovery may have to delete.
  std::string journal = std::string(kJournalHeader) + "\n";
  for (const std::string& n : final_names) journal += n + "\n";
  for (const std::string& n : current.files) {
    if (new_files.count(n) == 0 && plainFileName(n)) journal += n + "\n";
  }
  Status js = writeFileAtomic(staging + "/" + kJournalFileName,
                              std::vector<uint8_t>(journal.begin(), journal.end()));
  if (!js) return R::failure(js.error());

  // 3. Move the tiles in. None of the names is the current map's, so it stays whole.
  size_t moved = 0;
  auto rollback = [&](const std::string& why) {
    for (size_t i = 0; i < moved; ++i) ::unlink((dir + "/" + final_names[i]).c_str());
    syncDirectory(dir);
    return R::failure(why);
  };
  for (; moved < staged.size(); ++moved) {
    const std::string from = staging + "/" + staged[moved];
    const std::string to = dir + "/" + final_names[moved];
    if (::rename(from.c_str(), to.c_str()) != 0) {
      return rollback("cannot move tile file '" + from + "' to '" + to + "': " + errnoText(errno));
    }
  }
  syncDirectory(dir);

  // 4. The commit: one rename of the new manifest over the old one.
  for (size_t i = 0; i < manifest.tiles.size(); ++i) manifest.tiles[i].file_name = final_names[i];
  const std::vector<uint8_t> bytes = encodeManifest(manifest);
  const std::string staged_manifest = staging + "/" + kStagedManifestName;
  Status ms = writeFileAtomic(staged_manifest, bytes);
  if (!ms) return rollback(ms.error());
  const std::string target = dir + "/" + kManifestFileName;
  if (::rename(staged_manifest.c_str(), target.c_str()) != 0) {
    return rollback("cannot rename '" + staged_manifest + "' to '" + target +
                    "': " + errnoText(errno));
  }
  syncDirectory(dir);

  // 5. Retire the old map's tiles (a kill here leaves them to the next build's recovery).
  for (const std::string& n : current.files) {
    if (new_files.count(n) == 0 && plainFileName(n)) ::unlink((dir + "/" + n).c_str());
  }
  syncDirectory(dir);
  return static_cast<uint64_t>(bytes.size());
}

}  // namespace map_builder
}  // namespace gmm_localization
