#include "build_map/pcd_reader.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "build_map/lzf.h"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the PCD reader decodes binary data as little-endian (host order)");

namespace gmm_localization {
namespace tools {
namespace {

/// LZF's best case: a 3-byte back-reference produces 264 bytes.
constexpr uint64_t kMaxLzfRatio = 88;

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
  token_ = {0, 0, 0, 0};
  const int idx[4] = {header_.x, header_.y, header_.z, std::max(header_.intensity, 0)};
  for (int k = 0; k < 4; ++k) {
    for (int i = 0; i < idx[k]; ++i) token_[k] += header_.fields[i].count;
  }
  if (::fseeko(file_, static_cast<off_t>(header_.data_offset), SEEK_SET) != 0)
    return Status::failure(fail("cannot seek to the data"));
  ascii_line_ = header_lines_;
  std::vector<Eigen::Vector3d> none;
  auto n = readAscii(header_.points, none, false, nullptr);
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

Result<size_t> PcdFileReader::readAscii(size_t n, std::vector<Eigen::Vector3d>& xyz, bool keep,
                                        std::vector<float>* intensity) {
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
    double v[4] = {0, 0, 0, 0};
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
                               quotedPcdToken(std::string(p, w)) + " is not a number"));
      }
      for (int k = 0; k < 4; ++k)
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
    if (keep && intensity) intensity->push_back(static_cast<float>(v[3]));
    ++got;
    ++next_;
  }
  return got;
}

Result<size_t> PcdFileReader::read(size_t max_points, std::vector<Eigen::Vector3d>& xyz,
                                   std::vector<float>* intensity) {
  using R = Result<size_t>;
  const PcdHeader& h = header_;
  const size_t n = static_cast<size_t>(std::min<uint64_t>(max_points, h.points - next_));
  if (n == 0) return size_t{0};
  if (h.intensity < 0) intensity = nullptr;
  if (h.data == PcdData::kAscii) return readAscii(n, xyz, true, intensity);
  const PcdField* f[3] = {&h.fields[h.x], &h.fields[h.y], &h.fields[h.z]};
  const PcdField* fi = intensity ? &h.fields[h.intensity] : nullptr;
  xyz.reserve(xyz.size() + n);
  if (intensity) intensity->reserve(intensity->size() + n);
  if (h.data == PcdData::kBinary) {
    buffer_.resize(n * h.point_bytes);
    if (std::fread(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
      return R::failure(fail("the binary data ends early (the file changed while being read?)"));
    for (size_t i = 0; i < n; ++i) {
      const uint8_t* rec = buffer_.data() + i * h.point_bytes;
      xyz.emplace_back(decode(rec + f[0]->offset, *f[0]), decode(rec + f[1]->offset, *f[1]),
                       decode(rec + f[2]->offset, *f[2]));
      if (fi) intensity->push_back(static_cast<float>(decode(rec + fi->offset, *fi)));
    }
  } else {
    // Column-wise: field k's block starts at points * (bytes of the fields before it).
    const uint8_t* col[3];
    for (int k = 0; k < 3; ++k) col[k] = buffer_.data() + h.points * f[k]->offset;
    const uint8_t* col_i = fi ? buffer_.data() + h.points * fi->offset : nullptr;
    for (size_t i = 0; i < n; ++i) {
      const uint64_t j = next_ + i;
      xyz.emplace_back(decode(col[0] + j * f[0]->size, *f[0]),
                       decode(col[1] + j * f[1]->size, *f[1]),
                       decode(col[2] + j * f[2]->size, *f[2]));
      if (fi) intensity->push_back(static_cast<float>(decode(col_i + j * fi->size, *fi)));
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
