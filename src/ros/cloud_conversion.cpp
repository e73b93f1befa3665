#include "gmm_localization/ros/cloud_conversion.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace gmm_localization {
namespace node {
namespace {

using sensor_msgs::PointField;

const PointField* findField(const sensor_msgs::PointCloud2& msg, const std::string& name) {
  for (const PointField& f : msg.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

size_t typeSize(uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8:
    case PointField::UINT8:
      return 1;
    case PointField::INT16:
    case PointField::UINT16:
      return 2;
    case PointField::INT32:
    case PointField::UINT32:
    case PointField::FLOAT32:
      return 4;
    case PointField::FLOAT64:
      return 8;
    default:
      return 0;
  }
}

template <typename T>
T readAs(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

/// Reads a numeric field as double (host byte order; big-endian clouds are rejected earlier).
double readNumber(const uint8_t* p, uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8:
      return readAs<int8_t>(p);
    case PointField::UINT8:
      return readAs<uint8_t>(p);
    case PointField::INT16:
      return readAs<int16_t>(p);
    case PointField::UINT16:
      return readAs<uint16_t>(p);
    case PointField::INT32:
      return readAs<int32_t>(p);
    case PointField::UINT32:
      return readAs<uint32_t>(p);
    case PointField::FLOAT32:
      return readAs<float>(p);
    default:
      return readAs<double>(p);
  }
}

std::string checkField(const PointField* f, uint32_t point_step) {
  if (f == nullptr) return {};
  const size_t size = typeSize(f->datatype);
  if (size == 0)
    return "field '" + f->name + "' has unknown datatype " + std::to_string(f->datatype);
  if (f->count < 1) return "field '" + f->name + "' has count 0";
  if (f->offset + size > point_step) {
    return "field '" + f->name + "' (offset " + std::to_string(f->offset) +
           ") does not fit in point_step " + std::to_string(point_step);
  }
  return {};
}

/// double -> float without undefined behaviour: values beyond the float range become +-inf (as
/// non-finite points they are then dropped downstream), NaN stays NaN.
float toFloat(double v) {
  constexpr double kMax = std::numeric_limits<float>::max();
  if (v > kMax) return std::numeric_limits<float>::infinity();
  if (v < -kMax) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(v);
}

/// Empty when v (any numeric datatype read as double) is finite and in [0, max], else why.
std::string checkIntegerValue(const char* name, double v, double max, size_t point) {
  if (std::isfinite(v) && v >= 0.0 && v <= max) return {};
  std::ostringstream s;
  s << "field '" << name << "' of point " << point << " is " << v << ": not in [0, " << max << "]";
  return s.str();
}

}  // namespace

Result<CloudData> fromMsg(const sensor_msgs::PointCloud2& msg) {
  using R = Result<CloudData>;
  if (msg.is_bigendian) return R::failure("big-endian clouds are not supported");
  const uint64_t n = static_cast<uint64_t>(msg.width) * msg.height;
  if (msg.point_step == 0 && n > 0) return R::failure("point_step is 0");
  if (static_cast<uint64_t>(msg.row_step) * msg.height != msg.data.size()) {
    return R::failure("row_step " + std::to_string(msg.row_step) + " x height " +
                      std::to_string(msg.height) + " != data size " +
                      std::to_string(msg.data.size()));
  }
  if (static_cast<uint64_t>(msg.point_step) * msg.width > msg.row_step) {
    return R::failure("point_step " + std::to_string(msg.point_step) + " x width " +
                      std::to_string(msg.width) + " exceeds row_step " +
                      std::to_string(msg.row_step));
  }
  const PointField* fx = findField(msg, "x");
  const PointField* fy = findField(msg, "y");
  const PointField* fz = findField(msg, "z");
  if (fx == nullptr || fy == nullptr || fz == nullptr) {
    return R::failure("cloud lacks an x, y or z field");
  }
  for (const PointField* f : {fx, fy, fz}) {
    if (f->datatype != PointField::FLOAT32 && f->datatype != PointField::FLOAT64) {
      return R::failure("field '" + f->name + "' must be float32 or float64");
    }
  }
  const PointField* ft = findField(msg, "time");
  if (ft == nullptr) ft = findField(msg, "t");
  const PointField* fi = findField(msg, "intensity");
  const PointField* fr = findField(msg, "ring");
  const PointField* fl = findField(msg, "label");
  for (const PointField* f : {fx, fy, fz, ft, fi, fr, fl}) {
    const std::string e = checkField(f, msg.point_step);
    if (!e.empty()) return R::failure(e);
  }
  // uint32 "t" is nanoseconds (Ouster); any float time is seconds.
  const double time_scale = (ft != nullptr && ft->datatype == PointField::UINT32) ? 1e-9 : 1.0;

  CloudData out;
  // Width or height 0: the empty cloud, every channel empty (the callers' "0 points" case: the
  // matcher drops it with a reason, the merger and evaluate pass it on). Returned before the
  // loops, which would otherwise visit every one of up to 2^32 - 1 empty rows: with no points
  // each size check above holds for any height, row_step 0 and no data.
  if (n == 0) return out;
  // From here width >= 1 and point_step >= 1, so row_step >= 1 and the data holds exactly
  // data.size() / row_step = height rows: the row loop is bounded by the data, not by height.
  const size_t rows = msg.data.size() / msg.row_step;
  if (rows != msg.height) {
    return R::failure("data of " + std::to_string(msg.data.size()) + " bytes holds " +
                      std::to_string(rows) + " rows of row_step " + std::to_string(msg.row_step) +
                      ", not height " + std::to_string(msg.height));
  }
  out.points.resize(n);
  if (ft) out.time_s.resize(n);
  if (fi) out.intensity.resize(n);
  if (fr) out.ring.resize(n);
  if (fl) out.label.resize(n);
  size_t i = 0;
  for (size_t row = 0; row < rows; ++row) {
    const uint8_t* base = msg.data.data() + row * msg.row_step;
    for (uint32_t col = 0; col < msg.width; ++col, ++i) {
      const uint8_t* p = base + static_cast<size_t>(col) * msg.point_step;
      out.points[i] = Eigen::Vector3f(toFloat(readNumber(p + fx->offset, fx->datatype)),
                                      toFloat(readNumber(p + fy->offset, fy->datatype)),
                                      toFloat(readNumber(p + fz->offset, fz->datatype)));
      if (ft) out.time_s[i] = toFloat(readNumber(p + ft->offset, ft->datatype) * time_scale);
      if (fi) out.intensity[i] = toFloat(readNumber(p + fi->offset, fi->datatype));
      // Integer fields of any datatype: checked before the cast (a float -> integer cast of a
      // value out of range is undefined behaviour); fractions are truncated towards zero.
      if (fr) {
        const double v = readNumber(p + fr->offset, fr->datatype);
        const std::string e = checkIntegerValue("ring", v, 65535.0, i);
        if (!e.empty()) return R::failure(e);
        out.ring[i] = static_cast<uint16_t>(v);
      }
      if (fl) {
        const double v = readNumber(p + fl->offset, fl->datatype);
        const std::string e = checkIntegerValue("label", v, 255.0, i);
        if (!e.empty()) return R::failure(e);
        out.label[i] = static_cast<uint8_t>(v);
      }
    }
  }
  return out;
}

void toMsg(const CloudData& cloud, sensor_msgs::PointCloud2& msg,
           const std::string& extra_float_name, const std::vector<float>& extra_float) {
  const size_t n = cloud.points.size();
  msg.fields.clear();
  uint32_t offset = 0;
  auto add = [&](const std::string& name, uint8_t type) {
    PointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = type;
    f.count = 1;
    msg.fields.push_back(f);
    offset += static_cast<uint32_t>(typeSize(type));
  };
  add("x", PointField::FLOAT32);
  add("y", PointField::FLOAT32);
  add("z", PointField::FLOAT32);
  const bool has_i = cloud.intensity.size() == n, has_t = cloud.time_s.size() == n;
  const bool has_r = cloud.ring.size() == n, has_l = cloud.label.size() == n;
  const bool has_e = !extra_float_name.empty() && extra_float.size() == n;
  if (has_i) add("intensity", PointField::FLOAT32);
  if (has_t) add("time", PointField::FLOAT32);
  if (has_e) add(extra_float_name, PointField::FLOAT32);
  if (has_r) add("ring", PointField::UINT16);
  if (has_l) add("label", PointField::UINT8);
  msg.height = 1;
  msg.width = static_cast<uint32_t>(n);
  msg.is_bigendian = false;
  msg.is_dense = false;
  msg.point_step = offset;
  msg.row_step = offset * msg.width;
  msg.data.resize(static_cast<size_t>(msg.row_step));
  for (size_t i = 0; i < n; ++i) {
    uint8_t* p = msg.data.data() + i * offset;
    auto put = [&p](const void* v, size_t size) {
      std::memcpy(p, v, size);
      p += size;
    };
    put(cloud.points[i].data(), 3 * sizeof(float));
    if (has_i) put(&cloud.intensity[i], sizeof(float));
    if (has_t) put(&cloud.time_s[i], sizeof(float));
    if (has_e) put(&extra_float[i], sizeof(float));
    if (has_r) put(&cloud.ring[i], sizeof(uint16_t));
    if (has_l) put(&cloud.label[i], sizeof(uint8_t));
  }
}

}  // namespace node
}  // namespace gmm_localization
