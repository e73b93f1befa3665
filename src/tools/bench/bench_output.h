#pragma once
// bench_registration's per-run output (--out DIR): the report as printed (summary.md), one CSV
// row per registration (scans.csv) and the summary as JSON (summary.json).

#include <cstdio>
#include <string>
#include <vector>

namespace gmm_localization {
namespace bench {

/// The report: printed to stdout and kept, for summary.md.
class Report {
 public:
  void print(const char* format, ...) __attribute__((format(printf, 2, 3)));
  const std::string& text() const { return text_; }

 private:
  std::string text_;
};

/// One registration of one scan.
struct ScanRecord {
  std::string section;  ///< "window", "scan size 20000", "global", "peers"
  std::string window;   ///< the row's name
  std::string matcher = "gmm_localization";
  int scan = 0;
  double raw_points = 0.0, search_points = 0.0;
  double offset_m = 0.0, offset_deg = 0.0;  ///< the prior's error
  bool matched = false;
  double error_m = 0.0, error_deg = 0.0;                        ///< after the match (matched only)
  bool success = false;                                         ///< < 0.5 m and < 1 deg
  int certified = -1;                                           ///< -1: not applicable
  double prepare_ms = -1.0, search_ms = -1.0, total_ms = -1.0;  ///< -1: not measured
  double evaluations_fraction = -1.0;
  int equal_to_exhaustive = -1;  ///< -1: not compared
  std::string failure;
  /// The stages after the search (the last columns; -1: not measured).
  double refine_ms = -1.0, covariance_ms = -1.0, certificate_ms = -1.0, obstacles_ms = -1.0;
};

/// Writes the records as CSV (header line first); false on an I/O error.
bool writeScanCsv(const std::vector<ScanRecord>& records, const std::string& path);

/// A JSON object built member by member (insertion order kept); NaN and infinities are null.
class JsonObject {
 public:
  JsonObject& add(const std::string& key, double value);
  JsonObject& add(const std::string& key, int value) {
    return add(key, static_cast<long long>(value));
  }
  JsonObject& add(const std::string& key, long long value);
  JsonObject& add(const std::string& key, size_t value) {
    return add(key, static_cast<long long>(value));
  }
  JsonObject& add(const std::string& key, bool value);
  JsonObject& add(const std::string& key, const std::string& value);
  JsonObject& add(const std::string& key, const char* value) {
    return add(key, std::string(value));
  }
  JsonObject& add(const std::string& key, const JsonObject& value);
  JsonObject& add(const std::string& key, const std::vector<JsonObject>& values);
  JsonObject& add(const std::string& key, const std::vector<int>& values);
  /// One line per member at the top level, compact inside (arrays: one element a line).
  std::string text() const;
  std::string compact() const;

 private:
  std::vector<std::pair<std::string, std::string>> members_;  ///< key, rendered JSON value
};

std::string jsonQuote(const std::string& s);

/// Writes `text` to `path`; false on an I/O error.
bool writeTextFile(const std::string& path, const std::string& text);

}  // namespace bench
}  // namespace gmm_localization
