#include "gmm_localization/ros/cloud_conversion.h"

#include <algorithm>
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

const char* datatypeName(uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8:
      return "int8";
    case PointField::UINT8:
      return "uint8";
    case PointField::INT16:
      return "int16";
    case PointField::UINT16:
      return "uint16";
    case PointField::INT32:
      return "int32";
    case PointField::UINT32:
      return "uint32";
    case PointField::FLOAT32:
      return "float32";
    case PointField::FLOAT64:
      return "float64";
    default:
      return "unknown";
  }
}

/// One way to read raw time values: t = raw * scale - offset_s [s after the stamp].
struct TimeReading {
  PointTimeKind kind;
  double scale;
  double offset_s;
};

std::string number(double v, int precision = 9) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

}  // namespace

const char* const kPointTimeFields[3] = {"time", "t", "timestamp"};

const char* pointTimeKindName(PointTimeKind kind) {
  switch (kind) {
    case PointTimeKind::kRelativeSeconds:
      return "relative seconds";
    case PointTimeKind::kRelativeNanoseconds:
      return "relative nanoseconds";
    case PointTimeKind::kAbsoluteSeconds:
      return "absolute seconds";
    case PointTimeKind::kAbsoluteNanoseconds:
      return "absolute nanoseconds";
    case PointTimeKind::kRefused:
      return "refused";
    default:
      return "none";
  }
}

const char* pointTimeFixHint() {
  return "publish per-point times relative to header.stamp (float32 seconds 'time' or uint32 "
         "nanoseconds 't') or absolute float64 times ('timestamp', seconds or nanoseconds since "
         "the epoch) on the clock of header.stamp and within 1 s of it (check the driver's time "
         "source and clock synchronisation, e.g. PTP)";
}

std::string describePointTimes(const CloudData& cloud) {
  if (cloud.time_kind == PointTimeKind::kNone || cloud.time_kind == PointTimeKind::kRefused) {
    return {};
  }
  return "'" + cloud.time_field + "' " + datatypeName(cloud.time_datatype) + " " +
         pointTimeKindName(cloud.time_kind);
}

PointTimes interpretPointTimes(const std::string& field, uint8_t datatype,
                               const std::vector<double>& raw, const std::vector<bool>& usable,
                               const ros::Time& stamp) {
  PointTimes out;
  const std::string name = "per-point '" + field + "' (" + datatypeName(datatype) + ")";
  auto refuse = [&](const std::string& why) {
    out.kind = PointTimeKind::kRefused;
    out.time_s.clear();
    out.problem = name + " " + why;
    return out;
  };
  const bool is_float = datatype == PointField::FLOAT32 || datatype == PointField::FLOAT64;
  if (!is_float && typeSize(datatype) != 4) {
    return refuse("has a unit that is unknown (1- and 2-byte integer times are not read)");
  }
  // The usable values' extremes; a usable point without a finite time refuses them all.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  size_t n_usable = 0, n_nonfinite = 0;
  for (size_t i = 0; i < raw.size(); ++i) {
    if (!usable.empty() && !usable[i]) continue;
    ++n_usable;
    if (!std::isfinite(raw[i])) {
      ++n_nonfinite;
      continue;
    }
    lo = std::min(lo, raw[i]);
    hi = std::max(hi, raw[i]);
  }
  if (n_nonfinite > 0) {
    return refuse("is not finite for " + std::to_string(n_nonfinite) + " of the " +
                  std::to_string(n_usable) + " points with finite coordinates");
  }
  const double stamp_s = stamp.toSec();
  // The readings tried, in this order: for floats seconds after the stamp, or absolute seconds
  // or nanoseconds; for integers nanoseconds after the stamp (Ouster). Float nanoseconds after
  // the stamp are not tried: almost any garbage would pass as a few nanoseconds.
  const TimeReading float_readings[3] = {{PointTimeKind::kRelativeSeconds, 1.0, 0.0},
                                         {PointTimeKind::kAbsoluteSeconds, 1.0, stamp_s},
                                         {PointTimeKind::kAbsoluteNanoseconds, 1e-9, stamp_s}};
  const TimeReading integer_reading = {PointTimeKind::kRelativeNanoseconds, 1e-9, 0.0};
  const TimeReading* const first = is_float ? float_readings : &integer_reading;
  const TimeReading* const last = is_float ? float_readings + 3 : &integer_reading + 1;
  // A point's time: the chosen reading of its raw value (non-finite stays NaN).
  auto convert = [&](const TimeReading& r) {
    out.kind = r.kind;
    out.time_s.resize(raw.size());
    for (size_t i = 0; i < raw.size(); ++i) {
      out.time_s[i] = toFloat(raw[i] * r.scale - r.offset_s);
    }
    return out;
  };
  if (n_usable == 0) return convert(*first);  // no usable point: nothing to check
  // Resolution of the datatype at the values' magnitude, in seconds once scaled.
  const double magnitude = std::max(std::abs(lo), std::abs(hi));
  const double epsilon =
      datatype == PointField::FLOAT32 ? std::ldexp(1.0, -23) : std::ldexp(1.0, -52);
  struct Fit {
    double t_lo, t_hi, offset, quantum;
    bool ok;
  };
  auto fit = [&](const TimeReading& r) {
    Fit f;
    f.t_lo = lo * r.scale - r.offset_s;
    f.t_hi = hi * r.scale - r.offset_s;
    f.offset = std::max(std::abs(f.t_lo), std::abs(f.t_hi));
    f.quantum = is_float ? magnitude * epsilon * r.scale : r.scale;
    f.ok = f.offset <= kMaxPointTimeOffsetS && f.t_hi - f.t_lo <= kMaxPointTimeSpanS &&
           f.quantum <= kMaxPointTimeQuantumS;
    return f;
  };
  if (is_float) {
    // Relative and absolute seconds can both fit only for a stamp within a second of 0 (sim
    // time): the reading nearer the stamp wins, relative on a tie.
    const Fit rel = fit(float_readings[0]), abs_s = fit(float_readings[1]);
    if (rel.ok && abs_s.ok) {
      return convert(abs_s.offset < rel.offset ? float_readings[1] : float_readings[0]);
    }
  }
  for (const TimeReading* r = first; r != last; ++r) {
    if (fit(*r).ok) return convert(*r);
  }
  // Refused: explained with the reading that comes nearest to the stamp.
  const TimeReading* best = first;
  for (const TimeReading* r = first; r != last; ++r) {
    if (fit(*r).offset < fit(*best).offset) best = r;
  }
  const Fit f = fit(*best);
  std::string why = "makes no sense: values " + number(lo, 12) + " .. " + number(hi, 12) +
                    " at stamp " + number(stamp_s, 13) + " s, read as " +
                    pointTimeKindName(best->kind) + ", lie " + number(f.t_lo, 4) + " .. " +
                    number(f.t_hi, 4) + " s from the stamp";
  if (f.quantum > kMaxPointTimeQuantumS) {
    why += ", in steps of " + number(f.quantum, 3) + " s (too coarse: use float64)";
  } else if (f.offset <= kMaxPointTimeOffsetS) {
    why += " (a span over " + number(kMaxPointTimeSpanS) + " s)";
  } else {
    why += " (more than " + number(kMaxPointTimeOffsetS) + " s away)";
  }
  return refuse(why + "; deskewing needs every time within " + number(kMaxPointTimeOffsetS) +
                " s of the stamp, in s after it (float), ns after it (integer) or absolute s or ns "
                "(float64)");
}

Result<CloudData> fromMsg(const sensor_msgs::PointCloud2& msg, const std::string& time_field) {
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
  // The per-point time fields present, in the order they are tried.
  std::vector<const PointField*> time_fields;
  if (!time_field.empty()) {
    if (const PointField* f = findField(msg, time_field)) time_fields.push_back(f);
  } else {
    for (const char* name : kPointTimeFields) {
      if (const PointField* f = findField(msg, name)) time_fields.push_back(f);
    }
  }
  const PointField* fi = findField(msg, "intensity");
  const PointField* fr = findField(msg, "ring");
  const PointField* fl = findField(msg, "label");
  for (const PointField* f : {fx, fy, fz, fi, fr, fl}) {
    const std::string e = checkField(f, msg.point_step);
    if (!e.empty()) return R::failure(e);
  }
  for (const PointField* f : time_fields) {
    const std::string e = checkField(f, msg.point_step);
    if (!e.empty()) return R::failure(e);
  }

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
  // Raw time values (as double), interpreted once every point is read.
  std::vector<std::vector<double>> raw_times(time_fields.size(), std::vector<double>(n));
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
      for (size_t k = 0; k < time_fields.size(); ++k) {
        raw_times[k][i] = readNumber(p + time_fields[k]->offset, time_fields[k]->datatype);
      }
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
  if (!time_fields.empty()) {
    // The first field whose times make sense; when none does, the scan is not deskewed.
    std::vector<bool> usable(n);
    for (size_t j = 0; j < n; ++j) usable[j] = out.points[j].allFinite();
    std::string problems;
    for (size_t k = 0; k < time_fields.size(); ++k) {
      PointTimes t = interpretPointTimes(time_fields[k]->name, time_fields[k]->datatype,
                                         raw_times[k], usable, msg.header.stamp);
      if (t.kind != PointTimeKind::kRefused) {
        out.time_s = std::move(t.time_s);
        out.time_field = time_fields[k]->name;
        out.time_datatype = time_fields[k]->datatype;
        out.time_kind = t.kind;
        problems.clear();
        break;
      }
      problems += (problems.empty() ? "" : "; ") + t.problem;
    }
    if (!problems.empty()) {
      out.time_field = time_fields.front()->name;
      out.time_datatype = time_fields.front()->datatype;
      out.time_kind = PointTimeKind::kRefused;
      out.time_problem = std::move(problems);
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
