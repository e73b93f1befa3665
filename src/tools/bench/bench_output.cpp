#include "bench/bench_output.h"

#include <cmath>
#include <cstdarg>
#include <fstream>

namespace gmm_localization {
namespace bench {

void Report::print(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  if (n > 0) {
    std::string buf(static_cast<size_t>(n) + 1, '\0');
    std::vsnprintf(&buf[0], buf.size(), format, args);
    buf.resize(static_cast<size_t>(n));
    std::fwrite(buf.data(), 1, buf.size(), stdout);
    text_ += buf;
  }
  va_end(args);
}

namespace {

std::string number(double v) {
  if (!std::isfinite(v)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string measured(double v) { return v < 0.0 ? std::string() : number(v); }

std::string csvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c == '\n' ? ' ' : c;
  }
  return out + "\"";
}

std::string flag(int v) { return v < 0 ? std::string() : std::to_string(v); }

}  // namespace

bool writeScanCsv(const std::vector<ScanRecord>& records, const std::string& path) {
  std::ofstream f(path);
  f << "section,window,matcher,scan,raw_points,search_points,offset_m,offset_deg,matched,"
       "error_m,error_deg,success,certified,prepare_ms,search_ms,total_ms,"
       "evaluations_fraction,equal_to_exhaustive,failure,refine_ms,covariance_ms,certificate_ms,"
       "obstacles_ms\n";
  for (const ScanRecord& r : records) {
    f << csvField(r.section) << ',' << csvField(r.window) << ',' << csvField(r.matcher) << ','
      << r.scan << ',' << number(r.raw_points) << ',' << measured(r.search_points) << ','
      << number(r.offset_m) << ',' << number(r.offset_deg) << ',' << (r.matched ? 1 : 0) << ','
      << (r.matched ? number(r.error_m) : "") << ',' << (r.matched ? number(r.error_deg) : "")
      << ',' << (r.success ? 1 : 0) << ',' << flag(r.certified) << ',' << measured(r.prepare_ms)
      << ',' << measured(r.search_ms) << ',' << measured(r.total_ms) << ','
      << measured(r.evaluations_fraction) << ',' << flag(r.equal_to_exhaustive) << ','
      << csvField(r.failure) << ',' << measured(r.refine_ms) << ',' << measured(r.covariance_ms)
      << ',' << measured(r.certificate_ms) << ',' << measured(r.obstacles_ms) << '\n';
  }
  f.close();
  return static_cast<bool>(f);
}

std::string jsonQuote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

JsonObject& JsonObject::add(const std::string& key, double value) {
  members_.emplace_back(key, std::isfinite(value) ? number(value) : "null");
  return *this;
}

JsonObject& JsonObject::add(const std::string& key, long long value) {
  members_.emplace_back(key, std::to_string(value));
  return *this;
}

JsonObject& JsonObject::add(const std::string& key, bool value) {
  members_.emplace_back(key, value ? "true" : "false");
  return *this;
}

JsonObject& JsonObject::add(const std::string& key, const std::string& value) {
  members_.emplace_back(key, jsonQuote(value));
  return *this;
}

JsonObject& JsonObject::add(const std::string& key, const JsonObject& value) {
  members_.emplace_back(key, value.compact());
  return *this;
}

JsonObject& JsonObject::add(const std::string& key, const std::vector<JsonObject>& values) {
  std::string t = "[";
  for (size_t i = 0; i < values.size(); ++i) {
    t += (i ? ",\n    " : "\n    ") + values[i].compact();
  }
  members_.emplace_back(key, t + (values.empty() ? "]" : "\n  ]"));
  return *this;
}

JsonObject& JsonObject::add(const std::string& key, const std::vector<int>& values) {
  std::string t = "[";
  for (size_t i = 0; i < values.size(); ++i) t += (i ? ", " : "") + std::to_string(values[i]);
  members_.emplace_back(key, t + "]");
  return *this;
}

std::string JsonObject::compact() const {
  std::string t = "{";
  for (size_t i = 0; i < members_.size(); ++i) {
    t += (i ? ", " : "") + jsonQuote(members_[i].first) + ": " + members_[i].second;
  }
  return t + "}";
}

std::string JsonObject::text() const {
  std::string t = "{\n";
  for (size_t i = 0; i < members_.size(); ++i) {
    t += "  " + jsonQuote(members_[i].first) + ": " + members_[i].second +
         (i + 1 < members_.size() ? ",\n" : "\n");
  }
  return t + "}\n";
}

bool writeTextFile(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
  f.close();
  return static_cast<bool>(f);
}

}  // namespace bench
}  // namespace gmm_localization
