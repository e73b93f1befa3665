#include "build_map/pcd_reader.h"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <sstream>

#include "build_map/lzf.h"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the PCD reader decodes binary data as little-endian (host order)");

namespace gmm_localization {
namespace tools {
namespace {

constexpr size_t kMaxFields = 4096;
constexpr int kMaxCount = 65536;
constexpr uint64_t kMaxDimension = uint64_t{1} << 40;
constexpr uint64_t kMaxDataBytes = uint64_t{1} << 50;
/// LZF's best case: a 3-byte back-reference produces 264 bytes.
constexpr uint64_t kMaxLzfRatio = 88;

/// A token for an error message: at most 40 characters, control bytes shown as '?'.
std::string quotedText(const std::string& s) {
  std::string q = s.substr(0, 40);
  for (char& c : q)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return "'" + q + (s.size() > 40 ? "...'" : "'");
}

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

double decode(const uint8_t* p, const PcdField& f) {
  switch (f.type) {
    case 'F':
      if (f.size == 4) {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      } else {
        double v;
        std::memcpy(&v, p, 8);
        return v;
      }
    case 'I':
      switch (f.size) {
        case 1:
          return static_cast<int8_t>(*p);
        case 2: {
          int16_t v;
          std::memcpy(&v, p, 2);
          return v;
        }
        case 4: {
          int32_t v;
          std::memcpy(&v, p, 4);
          return v;
        }
        default: {
          int64_t v;
          std::memcpy(&v, p, 8);
          return static_cast<double>(v);
        }
      }
    default:
      switch (f.size) {
        case 1:
          return *p;
        case 2: {
          uint16_t v;
          std::memcpy(&v, p, 2);
          return v;
        }
        case 4: {
          uint32_t v;
          std::memcpy(&v, p, 4);
          return v;
        }
        default: {
          uint64_t v;
          std::memcpy(&v, p, 8);
          return static_cast<double>(v);
        }
      }
  }
}

}  // namespace

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
                        quotedText(t[0]) + " (a garbled header, or not a PCD file)");
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
    return R::failure(at("DATA") + ": DATA " + quotedText(kind) +
                      " is not ascii, binary or binary_compressed");
  if (values.count("VERSION")) {
    const auto& v = args("VERSION");
    static const char* kVersions[] = {"0.7", ".7", "0.6", ".6", "0.5", ".5"};
    bool ok = v.size() == 1;
    bool known = false;
    for (const char* k : kVersions) known = known || (ok && v[0] == k);
    if (!known) {
      return R::failure(at("VERSION") + ": VERSION " + (v.empty() ? "''" : quotedText(v[0])) +
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
      return R::failure(at("SIZE") + ": SIZE " + quotedText(args("SIZE")[i]) + " of field " +
                        quotedText(f.name) + " is not 1, 2, 4 or 8");
    }
    const std::string& type = args("TYPE")[i];
    if (type != "F" && type != "I" && type != "U") {
      return R::failure(at("TYPE") + ": TYPE " + quotedText(type) + " of field " +
                        quotedText(f.name) + " is not F, I or U");
    }
    if (type == "F" && size != 4 && size != 8) {
      return R::failure(at("TYPE") + ": field " + quotedText(f.name) + " is F" +
                        std::to_string(size) + " (floats are F4 or F8)");
    }
    if (values.count("COUNT") && (!parseUnsigned(args("COUNT")[i], kMaxCount, count) || !count)) {
      return R::failure(at("COUNT") + ": COUNT " + quotedText(args("COUNT")[i]) + " of field " +
                        quotedText(f.name) + " is not in [1, " + std::to_string(kMaxCount) + "]");
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
      return at(key) + ": " + key + " " + (args(key).empty() ? "''" : quotedText(args(key)[0])) +
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

// ---------------------------------------------------------------------------------------------

PcdFileReader::~PcdFileReader() {
  if (file_) std::fclose(file_);
  std::free(line_);
}

std::string PcdFileReader::fail(const std::string& why) const {
  return "PCD file '" + path_ + "': " + why;
}

Result<std::unique_ptr<PcdFileReader>> PcdFileReader::open(const std::string& path) {
  using R = Result<std::unique_ptr<PcdFileReader>>;
  std::unique_ptr<PcdFileReader> r(new PcdFileReader());
  r->path_ = path;
  r->file_ = std::fopen(path.c_str(), "rb");
  if (!r->file_) return R::failure(r->fail(std::string("cannot open: ") + std::strerror(errno)));
  struct stat st;
  if (::fstat(::fileno(r->file_), &st) != 0 || !S_ISREG(st.st_mode))
    return R::failure(r->fail("not a regular file"));
  const uint64_t file_bytes = static_cast<uint64_t>(st.st_size);
  if (file_bytes == 0) return R::failure(r->fail("empty file"));
  std::string text(std::min<uint64_t>(file_bytes, kMaxPcdHeaderBytes), '\0');
  if (std::fread(&text[0], 1, text.size(), r->file_) != text.size())
    return R::failure(r->fail("cannot read the header"));
  auto h = parsePcdHeader(text);
  if (!h) return R::failure(r->fail(h.error()));
  r->header_ = *h;
  const PcdHeader& hd = r->header_;
  for (size_t i = 0; i < hd.data_offset; ++i) r->header_lines_ += text[i] == '\n';
  if (!hd.viewpointIsIdentity()) {
    r->notes_.push_back(
        r->fail("VIEWPOINT is not identity; it is not applied (as in PCL): give --transform if the "
                "points are in a sensor frame"));
  }
  Status s = hd.data == PcdData::kBinary             ? r->checkBinary(file_bytes)
             : hd.data == PcdData::kBinaryCompressed ? r->loadCompressed(file_bytes)
                                                     : r->scanAscii();
  if (!s) return R::failure(s.error());
  return R(std::move(r));
}

Status PcdFileReader::checkBinary(uint64_t file_bytes) {
  const uint64_t need = header_.points * header_.point_bytes;
  const uint64_t have = file_bytes - header_.data_offset;
  if (have < need) {
    return Status::failure(
        fail("DATA binary holds " + std::to_string(have) + " bytes but WIDTH x HEIGHT = " +
             std::to_string(header_.points) + " points of " + std::to_string(header_.point_bytes) +
             " bytes need " + std::to_string(need) + " (truncated file or wrong header)"));
  }
  if (have > need) {
    notes_.push_back(fail(std::to_string(have - need) +
                          " bytes after the last point are ignored (POINTS may be wrong)"));
  }
  if (::fseeko(file_, static_cast<off_t>(header_.data_offset), SEEK_SET) != 0)
    return Status::failure(fail("cannot seek to the data"));
  return Status::success();
}

Status PcdFileReader::loadCompressed(uint64_t file_bytes) {
  const uint64_t need = header_.points * header_.point_bytes;
  const uint64_t have = file_bytes - header_.data_offset;
  if (have < 8) {
    if (need == 0) return Status::success();
    return Status::failure(fail("DATA binary_compressed: " + std::to_string(have) +
                                " bytes of data, not even the two size words (truncated file)"));
  }
  uint32_t sizes[2];
  if (::fseeko(file_, static_cast<off_t>(header_.data_offset), SEEK_SET) != 0 ||
      std::fread(sizes, 4, 2, file_) != 2) {
    return Status::failure(fail("cannot read the compressed data's sizes"));
  }
  const uint64_t compressed = sizes[0], uncompressed = sizes[1];
  const std::string what = "DATA binary_compressed: ";
  if (uncompressed != need) {
    return Status::failure(fail(what + "the uncompressed size is " + std::to_string(uncompressed) +
                                " bytes but WIDTH x HEIGHT = " + std::to_string(header_.points) +
                                " points of " + std::to_string(header_.point_bytes) +
                                " bytes need " + std::to_string(need) + " (wrong header or size)"));
  }
  if (need == 0) return Status::success();
  if (compressed > have - 8) {
    return Status::failure(fail(what + "the compressed size is " + std::to_string(compressed) +
                                " bytes but only " + std::to_string(have - 8) +
                                " follow (truncated file or wrong size)"));
  }
  if (need > kMaxLzfRatio * compressed) {
    return Status::failure(fail(what + std::to_string(compressed) + " bytes of LZF cannot hold " +
                                std::to_string(need) + " bytes (at most " +
                                std::to_string(kMaxLzfRatio) + " times as many): a wrong size"));
  }
  if (have - 8 > compressed) {
    notes_.push_back(fail(std::to_string(have - 8 - compressed) +
                          " bytes after the compressed data are ignored"));
  }
  std::vector<uint8_t> packed(compressed);
  if (std::fread(packed.data(), 1, packed.size(), file_) != packed.size())
    return Status::failure(fail("cannot read the compressed data"));
  buffer_.resize(need);
  Status s = lzfDecompress(packed.data(), packed.size(), buffer_.data(), buffer_.size());
  if (!s) return Status::failure(fail(what + s.error() + " (corrupt data or wrong sizes)"));
  return Status::success();
}

Status PcdFileReader::scanAscii() {
  token_ = {0, 0, 0};
  const int idx[3] = {header_.x, header_.y, header_.z};
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < idx[k]; ++i) token_[k] += header_.fields[i].count;
  }
  if (::fseeko(file_, static_cast<off_t>(header_.data_offset), SEEK_SET) != 0)
    return Status::failure(fail("cannot seek to the data"));
  ascii_line_ = header_lines_;
  std::vector<Eigen::Vector3d> none;
  auto n = readAscii(header_.points, none, false);
  if (!n) return Status::failure(n.error());
  uint64_t extra = 0;
  for (ssize_t len; (len = ::getline(&line_, &line_capacity_, file_)) >= 0;) {
    for (ssize_t i = 0; i < len; ++i) {
      if (!std::isspace(static_cast<unsigned char>(line_[i]))) {
        ++extra;
        break;
      }
    }
  }
  if (extra > 0) {
    notes_.push_back(fail(std::to_string(extra) + " non-empty lines after POINTS " +
                          std::to_string(header_.points) + " points are ignored"));
  }
  next_ = 0;
  ascii_line_ = header_lines_;
  if (::fseeko(file_, static_cast<off_t>(header_.data_offset), SEEK_SET) != 0)
    return Status::failure(fail("cannot seek to the data"));
  return Status::success();
}

Result<size_t> PcdFileReader::readAscii(size_t n, std::vector<Eigen::Vector3d>& xyz, bool keep) {
  using R = Result<size_t>;
  size_t got = 0;
  while (got < n && next_ < header_.points) {
    const ssize_t len = ::getline(&line_, &line_capacity_, file_);
    if (len < 0) {
      if (std::ferror(file_)) return R::failure(fail("read error in the ascii data"));
      return R::failure(fail("the ascii data ends after " + std::to_string(next_) +
                             " points but the header says " + std::to_string(header_.points) +
                             " (truncated file or wrong header)"));
    }
    ++ascii_line_;
    char* p = line_;
    char* const end = line_ + len;
    if (std::memchr(p, '\0', len)) {
      return R::failure(fail("line " + std::to_string(ascii_line_) + " holds a NUL byte"));
    }
    double v[3] = {0, 0, 0};
    size_t t = 0;
    for (;;) {
      while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
      if (p >= end) break;
      char* e = nullptr;
      const double d = std::strtod(p, &e);
      if (e == p || (e < end && !std::isspace(static_cast<unsigned char>(*e)))) {
        char* w = p;
        while (w < end && !std::isspace(static_cast<unsigned char>(*w))) ++w;
        return R::failure(fail("line " + std::to_string(ascii_line_) + ": " +
                               quotedText(std::string(p, w)) + " is not a number"));
      }
      for (int k = 0; k < 3; ++k)
        if (t == token_[k]) v[k] = d;
      ++t;
      p = e;
    }
    if (t == 0) continue;  // blank line
    if (t != header_.tokens) {
      return R::failure(fail("line " + std::to_string(ascii_line_) + " has " + std::to_string(t) +
                             " numbers but the fields need " + std::to_string(header_.tokens)));
    }
    if (keep) xyz.emplace_back(v[0], v[1], v[2]);
    ++got;
    ++next_;
  }
  return got;
}

Result<size_t> PcdFileReader::read(size_t max_points, std::vector<Eigen::Vector3d>& xyz) {
  using R = Result<size_t>;
  const PcdHeader& h = header_;
  const size_t n = static_cast<size_t>(std::min<uint64_t>(max_points, h.points - next_));
  if (n == 0) return size_t{0};
  if (h.data == PcdData::kAscii) return readAscii(n, xyz, true);
  const PcdField* f[3] = {&h.fields[h.x], &h.fields[h.y], &h.fields[h.z]};
  xyz.reserve(xyz.size() + n);
  if (h.data == PcdData::kBinary) {
    buffer_.resize(n * h.point_bytes);
    if (std::fread(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
      return R::failure(fail("the binary data ends early (the file changed while being read?)"));
    for (size_t i = 0; i < n; ++i) {
      const uint8_t* rec = buffer_.data() + i * h.point_bytes;
      xyz.emplace_back(decode(rec + f[0]->offset, *f[0]), decode(rec + f[1]->offset, *f[1]),
                       decode(rec + f[2]->offset, *f[2]));
    }
  } else {
    // Column-wise: field k's block starts at points * (bytes of the fields before it).
    const uint8_t* col[3];
    for (int k = 0; k < 3; ++k) col[k] = buffer_.data() + h.points * f[k]->offset;
    for (size_t i = 0; i < n; ++i) {
      const uint64_t j = next_ + i;
      xyz.emplace_back(decode(col[0] + j * f[0]->size, *f[0]),
                       decode(col[1] + j * f[1]->size, *f[1]),
                       decode(col[2] + j * f[2]->size, *f[2]));
    }
  }
  next_ += n;
  if (next_ == h.points && h.data == PcdData::kBinaryCompressed) {
    buffer_.clear();
    buffer_.shrink_to_fit();
  }
  return n;
}

}  // namespace tools
}  // namespace gmm_localization
