// build_map --overwrite never destroys the old map (map_builder.h, "Replacing a map"): the tool
// runs as a child process on a short synthetic street and is killed with SIGKILL at points of
// both passes and of the swap, or runs out of space on a small tmpfs. After each, the old map's
// files must be byte-identical (or, after a kill that came after the commit, the new map must be
// whole), map_info (which checks every tile's size and CRC) must exit 0 and MapStore must open
// and verify it. Finally an uninterrupted overwrite must succeed and leave nothing behind.
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/inotify.h>
#include <sys/mount.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "../../unit/support/temp_dir.h"
#include "gmm_localization/core/map/map_store.h"

#ifndef GMM_BUILD_MAP_BINARY
#error "GMM_BUILD_MAP_BINARY (the path of the build_map executable) must be defined"
#endif
#ifndef GMM_MAP_INFO_BINARY
#error "GMM_MAP_INFO_BINARY (the path of the map_info executable) must be defined"
#endif

namespace gmm_localization {
namespace {

namespace fs = std::filesystem;
using Files = std::map<std::string, std::vector<uint8_t>>;
using Clock = std::chrono::steady_clock;

using testing::TempDir;

/// build_map on a 60 m synthetic street in 64-cell (12.8 m) tiles: a few seconds, ~60 tiles.
std::vector<std::string> buildMapArgs(const std::string& output, int seed,
                                      const std::vector<std::string>& extra = {}) {
  std::vector<std::string> a = {GMM_BUILD_MAP_BINARY,
                                "--synthetic-street",
                                "60",
                                "--seed",
                                std::to_string(seed),
                                "--tile-size",
                                "64",
                                "--output",
                                output,
                                "--quiet"};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

/// Starts `args` with stdout and stderr to `log_path`.
pid_t spawn(const std::vector<std::string>& args, const std::string& log_path) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
    }
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

std::string readText(const std::string& path) {
  auto bytes = readFileBytes(path);
  return bytes ? std::string(bytes->begin(), bytes->end()) : std::string();
}

struct RunOutcome {
  bool killed = false;  ///< SIGKILLed by the test (else it exited by itself)
  int exit_code = -1;   ///< when it exited
  std::string log;      ///< stdout and stderr
};

/// Runs `args`; kills it with SIGKILL as soon as `kill_when()` holds (polled every 0.2 ms).
RunOutcome run(const std::vector<std::string>& args, const std::string& log_path,
               const std::function<bool(pid_t)>& kill_when = {}) {
  RunOutcome out;
  const pid_t pid = spawn(args, log_path);
  EXPECT_GT(pid, 0);
  int status = 0;
  for (;;) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (kill_when && kill_when(pid)) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  out.killed = WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
  out.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  out.log = readText(log_path);
  return out;
}

/// Every regular file directly in `dir`, name -> bytes.
Files snapshot(const std::string& dir) {
  Files files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    auto bytes = readFileBytes(e.path().string());
    if (bytes) files[e.path().filename()] = *bytes;
  }
  return files;
}

std::vector<std::string> stagingDirectories(const std::string& dir) {
  std::vector<std::string> found;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (std::string(e.path().filename()).rfind(".gmm_build.", 0) == 0) {
      found.push_back(e.path().string());
    }
  }
  return found;
}

/// Entries of `dir` whose name starts with `prefix` (0 when dir does not exist).
size_t countEntries(const std::string& dir, const char* prefix) {
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return 0;
  size_t n = 0;
  while (const dirent* e = ::readdir(d))
    n += std::strncmp(e->d_name, prefix, std::strlen(prefix)) == 0;
  ::closedir(d);
  return n;
}

/// The staging directory of build_map process `pid` (its first builder).
std::string stagingOf(const std::string& dir, pid_t pid) {
  return dir + "/.gmm_build." + std::to_string(pid) + ".0";
}

int mapInfo(const std::string& dir, const std::string& log_path) {
  return run({GMM_MAP_INFO_BINARY, dir}, log_path).exit_code;
}

/// The map in `dir` passes map_info and MapStore's verification.
void expectSoundMap(const std::string& dir, const std::string& log_path) {
  EXPECT_EQ(mapInfo(dir, log_path), 0) << readText(log_path);
  auto store = MapStore::open(dir);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_TRUE(store->verify().empty());
  EXPECT_GT(store->tileIds().size(), 0u);
}

class BuildMapOverwrite : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = work_.path + "/map";
    log_ = work_.path + "/log.txt";
    const RunOutcome first = run(buildMapArgs(dir_, 1), log_);
    ASSERT_EQ(first.exit_code, 0) << first.log;
    old_ = snapshot(dir_);
    ASSERT_TRUE(old_.count(kManifestFileName));
    ASSERT_GT(old_.size(), 20u);
  }

  /// After a run that was killed or failed: the old map byte-identical (`strict`: and no other
  /// file beside it), or, when the kill came after the commit, the new map whole (then the old
  /// map is put back for the next run). Returns true when the old map was in place.
  bool checkAfterRun(const std::string& what, bool strict) {
    SCOPED_TRACE(what);
    const Files now = snapshot(dir_);
    EXPECT_TRUE(now.count(kManifestFileName)) << "no manifest";
    const bool old_in_place =
        now.count(kManifestFileName) && now.at(kManifestFileName) == old_.at(kManifestFileName);
    if (old_in_place) {
      for (const auto& [name, bytes] : old_) {
        EXPECT_TRUE(now.count(name) && now.at(name) == bytes) << name << " changed";
      }
      if (strict) {
        EXPECT_EQ(now.size(), old_.size()) << "files beside the old map";
      }
    } else {
      EXPECT_FALSE(strict) << "the kill came after the commit";
    }
    expectSoundMap(dir_, log_ + ".info");
    for (const std::string& s : stagingDirectories(dir_)) {
      EXPECT_FALSE(MapStore::open(s).ok()) << "a staging directory opens as a map: " << s;
    }
    if (!old_in_place) restoreOldMap();
    return old_in_place;
  }

  void restoreOldMap() {
    for (const auto& e : fs::directory_iterator(dir_)) {
      if (e.is_regular_file()) fs::remove(e.path());
    }
    for (const auto& [name, bytes] : old_) {
      ASSERT_TRUE(writeFileAtomic(dir_ + "/" + name, bytes).ok());
    }
  }

  TempDir work_{"gmm_build_map_overwrite"};
  std::string dir_, log_;
  Files old_;
};

TEST_F(BuildMapOverwrite, WithoutOverwriteTheMapIsRefused) {
  const RunOutcome r = run(buildMapArgs(dir_, 2), log_);
  EXPECT_EQ(r.exit_code, 1) << r.log;
  EXPECT_NE(r.log.find("already holds a map"), std::string::npos) << r.log;
  EXPECT_TRUE(snapshot(dir_) == old_);
  EXPECT_TRUE(stagingDirectories(dir_).empty());
}

TEST_F(BuildMapOverwrite, KilledAnywhereTheOldMapSurvives) {
  const size_t tiles = old_.size() - 1;
  const std::vector<std::string> overwrite = {"--overwrite"};
  const std::vector<std::string> small_spill = {"--overwrite", "--spill-buffer-mb", "1"};
  struct KillPoint {
    std::string name;
    std::vector<std::string> extra;
    std::function<bool(pid_t)> when;
    bool before_commit;  ///< the point is reached well before the swap
  };
  std::vector<KillPoint> points;
  points.push_back({"at start (staging directory created)", overwrite,
                    [&](pid_t p) { return fs::exists(stagingOf(dir_, p)); }, true});
  points.push_back({"pass 1, spill files on disk", small_spill,
                    [&](pid_t p) { return countEntries(stagingOf(dir_, p) + "/spill", "t_") >= 8; },
                    true});
  points.push_back({"pass 2, first tile written", overwrite,
                    [&](pid_t p) { return countEntries(stagingOf(dir_, p), "tile_") >= 1; }, true});
  points.push_back({"pass 2, half the tiles written", overwrite,
                    [&](pid_t p) { return countEntries(stagingOf(dir_, p), "tile_") >= tiles / 2; },
                    true});
  points.push_back({"pass 2, all but 4 tiles written", overwrite,
                    [&](pid_t p) { return countEntries(stagingOf(dir_, p), "tile_") + 4 >= tiles; },
                    true});
  // The swap: killed at the first file moved into the map directory (inotify), which lands
  // somewhere in the swap or, on a slow machine, after it.
  const int watch_fd = ::inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
  ASSERT_GE(watch_fd, 0) << std::strerror(errno);
  ASSERT_GE(::inotify_add_watch(watch_fd, dir_.c_str(), IN_MOVED_TO), 0) << std::strerror(errno);
  auto movedIn = [&](pid_t) {
    alignas(inotify_event) char buf[4096];
    return ::read(watch_fd, buf, sizeof buf) > 0;
  };
  points.push_back({"the swap, first file moved in", overwrite, movedIn, false});
  // And a range of delays over both passes.
  for (double delay_s : {0.05, 0.4, 0.9, 1.5, 2.2, 3.0}) {
    auto when = [delay_s, start = std::make_shared<Clock::time_point>()](pid_t) {
      if (*start == Clock::time_point()) *start = Clock::now();
      return std::chrono::duration<double>(Clock::now() - *start).count() >= delay_s;
    };
    char name[32];
    std::snprintf(name, sizeof name, "after %.2f s", delay_s);
    points.push_back({name, overwrite, when, false});
  }

  int old_in_place = 0;
  for (const KillPoint& k : points) {
    char buf[4096];
    while (::read(watch_fd, buf, sizeof buf) > 0) {
    }  // events of earlier runs and restores
    const RunOutcome r = run(buildMapArgs(dir_, 2, k.extra), log_, k.when);
    if (k.before_commit) {
      EXPECT_TRUE(r.killed) << k.name << ": not reached; " << r.log;
    }
    if (!r.killed) {
      EXPECT_EQ(r.exit_code, 0) << k.name << ": " << r.log;
    }
    const size_t tile_files = countEntries(dir_, "tile_");  // before a restore
    const bool in_place = checkAfterRun(k.name, k.before_commit);
    old_in_place += in_place;
    const std::string state = in_place ? "old map in place, " +
                                             std::to_string(tile_files + 1 - old_.size()) +
                                             " new tile file(s) moved in beside it"
                                       : std::string("new map committed");
    std::printf("[          ] %-38s %s; %s\n", k.name.c_str(),
                r.killed ? "killed" : "finished first", state.c_str());
  }
  ::close(watch_fd);
  EXPECT_GE(old_in_place, 5);
  std::printf(
      "[          ] %d of %zu kills left the old map in place (the rest came after the "
      "commit)\n",
      old_in_place, points.size());

  // Leftover staging directories of the killed runs are cleaned by the next build, which
  // succeeds and leaves exactly the new map.
  const RunOutcome r = run(buildMapArgs(dir_, 2, overwrite), log_);
  ASSERT_EQ(r.exit_code, 0) << r.log;
  EXPECT_TRUE(stagingDirectories(dir_).empty());
  const Files now = snapshot(dir_);
  EXPECT_NE(now.at(kManifestFileName), old_.at(kManifestFileName));
  auto store = MapStore::open(dir_);
  ASSERT_TRUE(store.ok()) << store.error();
  EXPECT_EQ(now.size(), store->tileIds().size() + 1) << "only the manifest and its tiles";
  size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir_)) entries += e.exists();
  EXPECT_EQ(entries, now.size()) << "no other entry in the map directory";
  expectSoundMap(dir_, log_ + ".info");
}

/// Bytes in use on the file system holding `path`.
uint64_t usedBytes(const std::string& path) {
  struct statvfs s;
  if (::statvfs(path.c_str(), &s) != 0) return 0;
  return uint64_t{s.f_blocks - s.f_bfree} * s.f_frsize;
}

TEST(BuildMapOverwriteFullDisk, RunsOutOfSpaceAndKeepsTheOldMap) {
  TempDir mount_point("gmm_build_map_overwrite"), outside("gmm_build_map_overwrite");
  const std::string mp = mount_point.path;
  if (::mount("tmpfs", mp.c_str(), "tmpfs", 0, "size=64m") != 0) {
    GTEST_SKIP() << "cannot mount a tmpfs on " << mp << " (" << std::strerror(errno)
                 << "): needs CAP_SYS_ADMIN";
  }
  struct Unmount {
    std::string path;
    ~Unmount() { ::umount2(path.c_str(), MNT_DETACH); }
  } unmount{mp};
  const std::string dir = mp + "/map", log = outside.path + "/log.txt";
  const RunOutcome first = run(buildMapArgs(dir, 1), log);
  ASSERT_EQ(first.exit_code, 0) << first.log;
  const Files old = snapshot(dir);
  const uint64_t used = usedBytes(mp);
  ASSERT_GT(used, 100000u);
  auto shrinkTo = [&](uint64_t bytes) {
    const std::string opts = "size=" + std::to_string((bytes + 4095) / 4096 * 4) + "k";
    ASSERT_EQ(::mount("tmpfs", mp.c_str(), "tmpfs", MS_REMOUNT, opts.c_str()), 0)
        << opts << ": " << std::strerror(errno);
  };
  struct Case {
    std::string name;
    uint64_t free_bytes;
    std::vector<std::string> extra;
  };
  const std::vector<Case> cases = {
      // Pass 1: the spill files (~10 MB) do not fit in 1 MB.
      {"pass 1 (spill files)", uint64_t{1} << 20, {"--spill-buffer-mb", "1"}},
      // Pass 2: spill files elsewhere, room for half the new map's tiles.
      {"pass 2 (tile files)", used / 2, {"--temp-dir", outside.path}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    shrinkTo(used + c.free_bytes);
    std::vector<std::string> extra = {"--overwrite"};
    extra.insert(extra.end(), c.extra.begin(), c.extra.end());
    const RunOutcome r = run(buildMapArgs(dir, 2, extra), log);
    EXPECT_EQ(r.exit_code, 1) << r.log;
    EXPECT_NE(r.log.find("no space left on device"), std::string::npos) << r.log;
    EXPECT_TRUE(snapshot(dir) == old) << "the old map changed";
    EXPECT_TRUE(stagingDirectories(dir).empty());
    EXPECT_EQ(usedBytes(mp), used) << "the failed build's files were not all removed";
    expectSoundMap(dir, log + ".info");
  }
  // With room again, the overwrite succeeds.
  shrinkTo(used + (uint64_t{32} << 20));
  const RunOutcome r = run(buildMapArgs(dir, 2, {"--overwrite"}), log);
  ASSERT_EQ(r.exit_code, 0) << r.log;
  expectSoundMap(dir, log + ".info");
  EXPECT_NE(snapshot(dir).at(kManifestFileName), old.at(kManifestFileName));
}

TEST(BuildMapCli, ResolutionOutsideTheMapFormatFailsAtOnceWithTheRange) {
  // 5e-4 m cells passed the builder's own check (> 0) and ended in a manifest the map format
  // refuses (after a build over a grid 160 000 times the size of the 0.2 m one).
  TempDir work("gmm_build_map_overwrite");
  const std::string dir = work.path + "/map";
  const auto t0 = Clock::now();
  const RunOutcome r = run(buildMapArgs(dir, 1, {"--resolution", "5e-4"}), work.path + "/log");
  EXPECT_FALSE(r.killed);
  EXPECT_NE(r.exit_code, 0) << r.log;
  EXPECT_NE(r.log.find("--resolution"), std::string::npos) << r.log;
  EXPECT_NE(r.log.find("[0.05, 10] m"), std::string::npos) << r.log;
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 10.0) << "refused up front";
  EXPECT_FALSE(fs::exists(dir + "/" + kManifestFileName));
}

}  // namespace
}  // namespace gmm_localization
