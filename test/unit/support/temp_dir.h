#pragma once
// Test support: a temporary directory, created empty under /tmp and removed with all it holds
// when the object goes out of scope.

#include <stdlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace gmm_localization {
namespace testing {

struct TempDir {
  /// Creates /tmp/<prefix>_XXXXXX (mkdtemp); throws std::runtime_error if that fails.
  explicit TempDir(const std::string& prefix = "gmm_test") {
    std::string tmpl = "/tmp/" + prefix + "_XXXXXX";
    if (::mkdtemp(&tmpl[0]) == nullptr) {
      const int error = errno;
      throw std::runtime_error("mkdtemp(" + tmpl + "): " + std::strerror(error));
    }
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;  // a destructor must not throw
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  /// The names of the entries directly in the directory, sorted.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(path)) {
      names.push_back(e.path().filename());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

  std::string path;
};

}  // namespace testing
}  // namespace gmm_localization
