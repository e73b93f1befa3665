// Map format: CRC, whole-file reads, atomic writes, and the manifest/tile file entry points.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <sstream>

#include "gmm_localization/core/common/errno_text.h"
#include "gmm_localization/core/map/map_format.h"

namespace gmm_localization {
namespace {

std::string joinPath(const std::string& dir, const std::string& name) {
  if (dir.empty()) return name;
  return dir.back() == '/' ? dir + name : dir + "/" + name;
}

std::string parentDir(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

}  // namespace

uint32_t crc32Of(const uint8_t* data, size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  while (size > 0) {
    const uInt chunk = static_cast<uInt>(std::min<size_t>(size, 1u << 30));
    crc = crc32(crc, data, chunk);
    data += chunk;
    size -= chunk;
  }
  return static_cast<uint32_t>(crc);
}

std::string tileFileName(const TileId& id) {
  return "tile_" + std::to_string(id.x) + "_" + std::to_string(id.y) + ".gmt";
}

Status writeFileAtomic(const std::string& path, const std::vector<uint8_t>& bytes) {
  static std::atomic<uint64_t> counter{0};
  const std::string dir = parentDir(path);
  const std::string base = path.substr(path.find_last_of('/') + 1);
  if (base.empty()) return Status::failure("cannot write '" + path + "': not a file name");
  const std::string tmp = joinPath(dir, "." + base + ".tmp." + std::to_string(getpid()) + "." +
                                            std::to_string(counter.fetch_add(1)));
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    return Status::failure("cannot write '" + path + "': creating temporary file '" + tmp +
                           "' failed: " + errnoText(errno));
  }
  auto abandon = [&](const std::string& what, int e) {
    ::close(fd);
    ::unlink(tmp.c_str());
    return Status::failure("cannot write '" + path + "': " + what + ": " + errnoText(e));
  };
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return abandon("write of " + std::to_string(bytes.size()) + " bytes failed after " +
                         std::to_string(done),
                     errno);
    }
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) return abandon("fsync failed", errno);
  if (::close(fd) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    return Status::failure("cannot write '" + path + "': close failed: " + errnoText(e));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    return Status::failure("cannot write '" + path + "': rename failed: " + errnoText(e));
  }
  // Make the rename itself durable (best effort: some file systems refuse a directory fsync).
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  return Status::success();
}

Result<std::vector<uint8_t>> readFileBytes(const std::string& path, uint64_t max_bytes) {
  using R = Result<std::vector<uint8_t>>;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int e = errno;
    if (e == ENOENT) return R::failure("file '" + path + "': missing (no such file)");
    return R::failure("file '" + path + "': cannot open: " + errnoText(e));
  }
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return R::failure("file '" + path + "': not a regular file");
  }
  if (static_cast<uint64_t>(st.st_size) > max_bytes) {
    ::close(fd);
    return R::failure("file '" + path + "': " + std::to_string(st.st_size) +
                      " bytes exceeds the limit of " + std::to_string(max_bytes));
  }
  std::vector<uint8_t> bytes(static_cast<size_t>(st.st_size));
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = errno;
      ::close(fd);
      return R::failure("file '" + path + "': read failed after " + std::to_string(done) +
                        " bytes" + (n < 0 ? ": " + errnoText(e) : std::string(" (file shrank)")));
    }
    done += static_cast<size_t>(n);
  }
  ::close(fd);
  return bytes;
}

Result<MapManifest> readManifest(const std::string& directory) {
  const std::string path = joinPath(directory, kManifestFileName);
  auto bytes = readFileBytes(path, uint64_t{1} << 30);
  if (!bytes) return Result<MapManifest>::failure("map manifest: " + bytes.error());
  return decodeManifest(bytes->data(), bytes->size(), path);
}

Status writeManifest(const std::string& directory, const MapManifest& manifest) {
  return writeFileAtomic(joinPath(directory, kManifestFileName), encodeManifest(manifest));
}

Result<std::shared_ptr<GmmTile>> readTileFile(const std::string& directory, const TileInfo& info,
                                              const MapGeometry& geometry) {
  using R = Result<std::shared_ptr<GmmTile>>;
  const std::string path = joinPath(directory, info.file_name);
  auto bytes = readFileBytes(path, info.byte_size + 1);
  if (!bytes) {
    // A file larger than the manifest says is also a size mismatch; say so plainly.
    struct stat st;
    if (::stat(path.c_str(), &st) == 0 && static_cast<uint64_t>(st.st_size) != info.byte_size) {
      return R::failure("tile file '" + path + "': size " + std::to_string(st.st_size) +
                        " bytes, manifest says " + std::to_string(info.byte_size) +
                        " (truncated, extended or replaced)");
    }
    return R::failure("tile " + tileFileName(info.id) + ": " + bytes.error());
  }
  if (bytes->size() != info.byte_size) {
    return R::failure("tile file '" + path + "': size " + std::to_string(bytes->size()) +
                      " bytes, manifest says " + std::to_string(info.byte_size) +
                      " (truncated, extended or replaced)");
  }
  // The CRC of everything before the trailer (a CRC over a message and its own CRC is a
  // constant, so the trailer is left out).
  const uint32_t crc = bytes->size() >= 4 ? crc32Of(bytes->data(), bytes->size() - 4) : 0;
  if (crc != info.crc32) {
    std::ostringstream s;
    s << "tile file '" << path << "': CRC-32 mismatch against the manifest (file 0x" << std::hex
      << crc << ", manifest 0x" << info.crc32 << "): corrupted or replaced";
    return R::failure(s.str());
  }
  return decodeTile(bytes->data(), bytes->size(), path, &info.id, geometry.tile_size_cells);
}

}  // namespace gmm_localization
