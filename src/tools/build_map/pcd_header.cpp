// PCD headers: parsing and checking (format in pcd_reader.h).
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>

#include "build_map/pcd_reader.h"

namespace gmm_localization {
namespace tools {
namespace {

constexpr size_t kMaxFields = 4096;
constexpr int kMaxCount = 65536;
constexpr uint64_t kMaxDimension = uint64_t{1} << 40;
constexpr uint64_t kMaxDataBytes = uint64_t{1} << 50;

bool parseUnsigned(const std::string& s, uint64_t max, uint64_t& out) {
  if (s.empty() || s.size() > 20) return false;
  for (char c : s)
    if (c < '0' || c > '9') return false;
  errno = 0;
  const unsigned long long v = std::strtoull(s.c_str(), nullptr, 10);
  if (errno != 0 || v > max) return false;
  out = v;
  return true;
}

bool parseFinite(const std::string& s, double& out) {
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return !s.empty() && *end == '\0' && std::isfinite(out);
}

std::vector<std::string> splitWhitespace(const std::string& line) {
  std::vector<std::string> t;
  std::istringstream s(line);
  for (std::string w; s >> w;) t.push_back(w);
  return t;
}

}  // namespace

std::string quotedPcdToken(const std::string& s) {
  std::string q = s.substr(0, 40);
  for (char& c : q)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return "'" + q + (s.size() > 40 ? "...'" : "'");
}

const char* PcdHeader::dataName(PcdData d) {
  switch (d) {
    case PcdData::kAscii:
      return "ascii";
    case PcdData::kBinary:
      return "binary";
    case PcdData::kBinaryCompressed:
      return "binary_compressed";
  }
  return "?";
}

bool PcdHeader::viewpointIsIdentity() const {
  const std::array<double, 7> id{{0, 0, 0, 1, 0, 0, 0}};
  for (int i = 0; i < 7; ++i)
    if (std::abs(viewpoint[i] - id[i]) > 1e-9) return false;
  return true;
}

std::string PcdHeader::describeFields() const {
  std::string s =
      "x " + fields[x].typeName() + " y " + fields[y].typeName() + " z " + fields[z].typeName();
  size_t others = fields.size() - 3;
  if (intensity >= 0) {
    s += ", " + fields[intensity].name + " " + fields[intensity].typeName();
    --others;
  }
  if (others > 0) s += ", " + std::to_string(others) + " more field" + (others > 1 ? "s" : "");
  return s;
}

Result<PcdHeader> parsePcdHeader(const std::string& text) {
  using R = Result<PcdHeader>;
  PcdHeader h;
  std::map<std::string, std::vector<std::string>> values;  // keyword -> its arguments
  std::map<std::string, int> line_of;
  size_t pos = 0;
  int line_no = 0;
  bool have_data = false;
  while (!have_data) {
    if (pos >= text.size()) {
      return R::failure(text.size() >= kMaxPcdHeaderBytes
                            ? "no DATA line in the first " + std::to_string(text.size()) +
                                  " bytes (not a PCD file?)"
                            : "the header ends without a DATA line (truncated or not a PCD file)");
    }
    size_t eol = text.find('\n', pos);
    const bool last = eol == std::string::npos;
    if (last) eol = text.size();
    std::string line = text.substr(pos, eol - pos);
    pos = last ? eol : eol + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    for (char c : line) {
      const auto u = static_cast<unsigned char>(c);
      if ((u < 0x20 && c != '\t') || u >= 0x7f) {
        return R::failure("header line " + std::to_string(line_no) +
                          " is not text (a garbled header, or not a PCD file)");
      }
    }
    std::vector<std::string> t = splitWhitespace(line);
    if (t.empty() || t[0][0] == '#') continue;
    std::string key = t[0];
    if (key == "COLUMNS") key = "FIELDS";  // PCD v0.5
    static const char* kKnown[] = {"VERSION", "FIELDS", "SIZE",      "TYPE",   "COUNT",
                                   "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
    bool known = false;
    for (const char* k : kKnown) known = known || key == k;
    if (!known) {
      return R::failure("header line " + std::to_string(line_no) + ": unknown keyword " +
                        quotedPcdToken(t[0]) + " (a garbled header, or not a PCD file)");
    }
    if (values.count(key)) {
      return R::failure("header line " + std::to_string(line_no) + ": " + key +
                        " repeated (first on line " + std::to_string(line_of[key]) + ")");
    }
    t.erase(t.begin());
    values[key] = t;
    line_of[key] = line_no;
    if (key == "DATA") {
      have_data = true;
      h.data_offset = pos;
    }
  }
  auto at = [&](const std::string& key) { return "header line " + std::to_string(line_of[key]); };
  auto args = [&](const std::string& key) -> const std::vector<std::string>& {
    return values[key];
  };

  // DATA, VERSION
  if (args("DATA").size() != 1) return R::failure(at("DATA") + ": DATA needs one word");
  const std::string& kind = args("DATA")[0];
  if (kind == "ascii")
    h.data = PcdData::kAscii;
  else if (kind == "binary")
    h.data = PcdData::kBinary;
  else if (kind == "binary_compressed")
    h.data = PcdData::kBinaryCompressed;
  else
    return R::failure(at("DATA") + ": DATA " + quotedPcdToken(kind) +
                      " is not ascii, binary or binary_compressed");
  if (values.count("VERSION")) {
    const auto& v = args("VERSION");
    static const char* kVersions[] = {"0.7", ".7", "0.6", ".6", "0.5", ".5"};
    bool ok = v.size() == 1;
    bool known = false;
    for (const char* k : kVersions) known = known || (ok && v[0] == k);
    if (!known) {
      return R::failure(at("VERSION") + ": VERSION " + (v.empty() ? "''" : quotedPcdToken(v[0])) +
                        " is not 0.5, 0.6 or 0.7");
    }
    h.version = v[0];
  }

  // FIELDS, SIZE, TYPE, COUNT
  for (const char* k : {"FIELDS", "SIZE", "TYPE"})
    if (!values.count(k)) return R::failure(std::string("the header has no ") + k + " line");
  const auto& names = args("FIELDS");
  if (names.empty()) return R::failure(at("FIELDS") + ": FIELDS lists no field");
  if (names.size() > kMaxFields) {
    return R::failure(at("FIELDS") + ": " + std::to_string(names.size()) + " fields (at most " +
                      std::to_string(kMaxFields) + ")");
  }
  for (const char* k : {"SIZE", "TYPE", "COUNT"}) {
    if (!values.count(k)) continue;
    if (args(k).size() != names.size()) {
      return R::failure(at(k) + ": " + k + " has " + std::to_string(args(k).size()) +
                        " entries for " + std::to_string(names.size()) + " FIELDS");
    }
  }
  size_t offset = 0;
  for (size_t i = 0; i < names.size(); ++i) {
    PcdField f;
    f.name = names[i];
    uint64_t size = 0, count = 1;
    if (!parseUnsigned(args("SIZE")[i], 8, size) ||
        (size != 1 && size != 2 && size != 4 && size != 8)) {
      return R::failure(at("SIZE") + ": SIZE " + quotedPcdToken(args("SIZE")[i]) + " of field " +
                        quotedPcdToken(f.name) + " is not 1, 2, 4 or 8");
    }
    const std::string& type = args("TYPE")[i];
    if (type != "F" && type != "I" && type != "U") {
      return R::failure(at("TYPE") + ": TYPE " + quotedPcdToken(type) + " of field " +
                        quotedPcdToken(f.name) + " is not F, I or U");
    }
    if (type == "F" && size != 4 && size != 8) {
      return R::failure(at("TYPE") + ": field " + quotedPcdToken(f.name) + " is F" +
                        std::to_string(size) + " (floats are F4 or F8)");
    }
    if (values.count("COUNT") && (!parseUnsigned(args("COUNT")[i], kMaxCount, count) || !count)) {
      return R::failure(at("COUNT") + ": COUNT " + quotedPcdToken(args("COUNT")[i]) + " of field " +
                        quotedPcdToken(f.name) + " is not in [1, " + std::to_string(kMaxCount) +
                        "]");
    }
    f.size = static_cast<int>(size);
    f.type = type[0];
    f.count = static_cast<int>(count);
    f.offset = offset;
    offset += f.bytes();
    h.tokens += f.count;
    h.fields.push_back(f);
  }
  h.point_bytes = offset;
  for (size_t i = 0; i < h.fields.size(); ++i) {
    const std::string& n = h.fields[i].name;
    int* slot = n == "x" ? &h.x : n == "y" ? &h.y : n == "z" ? &h.z : nullptr;
    if (slot) {
      if (*slot >= 0) return R::failure(at("FIELDS") + ": field '" + n + "' appears twice");
      if (h.fields[i].count != 1) {
        return R::failure(at("COUNT") + ": field '" + n + "' has COUNT " +
                          std::to_string(h.fields[i].count) + " (a coordinate needs 1)");
      }
      *slot = static_cast<int>(i);
    } else if (h.intensity < 0 && h.fields[i].count == 1 &&
               (n == "intensity" || n == "i" || n == "reflectivity")) {
      h.intensity = static_cast<int>(i);
    }
  }
  std::string missing;
  if (h.x < 0) missing += " x";
  if (h.y < 0) missing += " y";
  if (h.z < 0) missing += " z";
  if (!missing.empty()) {
    return R::failure(at("FIELDS") + ": no" + missing + " field (FIELDS is '" + [&] {
      std::string s;
      for (const auto& n : names) s += (s.empty() ? "" : " ") + n;
      return s.substr(0, 80);
    }() + "'); x, y and z are required");
  }

  // WIDTH, HEIGHT, POINTS
  auto dimension = [&](const char* key, uint64_t& out) -> std::string {
    if (!values.count(key)) return "";
    if (args(key).size() != 1 || !parseUnsigned(args(key)[0], kMaxDimension, out)) {
      return at(key) + ": " + key + " " +
             (args(key).empty() ? "''" : quotedPcdToken(args(key)[0])) +
             " is not a count in [0, 2^40]";
    }
    return "";
  };
  uint64_t points = 0;
  for (auto [key, out] : {std::pair<const char*, uint64_t*>{"WIDTH", &h.width},
                          {"HEIGHT", &h.height},
                          {"POINTS", &points}}) {
    const std::string e = dimension(key, *out);
    if (!e.empty()) return R::failure(e);
  }
  if (!values.count("WIDTH")) {
    if (!values.count("POINTS")) return R::failure("the header has neither WIDTH nor POINTS");
    h.width = points;
    h.height = 1;
  }
  if (h.height != 0 && h.width > kMaxDimension / h.height) {
    return R::failure("WIDTH x HEIGHT = " + std::to_string(h.width) + " x " +
                      std::to_string(h.height) + " is too large");
  }
  h.points = h.width * h.height;
  if (values.count("POINTS") && points != h.points) {
    return R::failure(at("POINTS") + ": POINTS " + std::to_string(points) +
                      " but WIDTH x HEIGHT = " + std::to_string(h.width) + " x " +
                      std::to_string(h.height) + " = " + std::to_string(h.points));
  }
  if (h.point_bytes > 0 && h.points > kMaxDataBytes / h.point_bytes) {
    return R::failure(std::to_string(h.points) + " points of " + std::to_string(h.point_bytes) +
                      " bytes are too many");
  }

  // VIEWPOINT
  if (values.count("VIEWPOINT")) {
    const auto& v = args("VIEWPOINT");
    bool ok = v.size() == 7;
    for (size_t i = 0; ok && i < 7; ++i) ok = parseFinite(v[i], h.viewpoint[i]);
    if (!ok)
      return R::failure(at("VIEWPOINT") + ": VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)");
  }
  return h;
}

}  // namespace tools
}  // namespace gmm_localization
