#pragma once
// Shared by the fuzz targets and the seed writer (make_seeds.cpp): a compact byte layout of the
// ROS messages the stack receives (sensor_msgs/PointCloud2, gmm_localization/RasterChunk and
// MapIndex), so that a fuzzer's bytes become a message whose every field - sizes, offsets,
// counts, flags - is chosen by the input, and a message written by the project's own toMsg
// becomes a seed. Not ROS's wire format: arrays here are as long as their bytes allow (a
// deserialised ROS message is always self-consistent in that respect), which keeps the
// fuzzer's mutations on the fields the parsers check.
//
// All values little-endian; reads past the end give 0 (and empty arrays). Layouts:
//   PointCloud2: u8 flags, u32 height, u32 width, u8 is_bigendian, u32 point_step, u32 row_step,
//     u8 is_dense, u8 field count (<= kMaxCloudFields), per field {u8 name length, name, u32
//     offset, u8 datatype, u32 count}, then data = every remaining byte. flags bit 0: row_step =
//     data size / height and data cut to row_step x height (passes the size check, so the
//     mutations reach the field checks and the decoding); bit 1: width = row_step / point_step.
//   RasterChunk: i32 chunk_x, i32 chunk_y, i32 shift, u64 map_version, u32 stamp sec, u32 nsec,
//     u8 layer count (<= kMaxChunkLayers), per layer {i32 z_shift, u64 spans_start, u64
//     values_start, u32 value_count}, then the arrays spans (u32), values (u8), component_count
//     (u8) and components (f32), each as u32 element count + elements.
//   MapIndex: u32 stamp sec, u32 nsec, u8 directory length + bytes, u64 map_version, f64
//     resolution_m, i32 tile_size_cells, f64 origin_x_m, f64 origin_y_m, f64 z_step_m, f64
//     ll_floor, f64 ll_ceiling, i32 num_layers, i32 z_coarsening_period, i32 chunk_shift,
//     arrays chunk_x and chunk_y (i32), u64 raster_bytes, f64 min_x_m, min_y_m, max_x_m,
//     max_y_m.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include <sensor_msgs/PointCloud2.h>
#include <boost/make_shared.hpp>

#include "gmm_localization/MapIndex.h"
#include "gmm_localization/RasterChunk.h"

namespace gmm_localization {
namespace fuzz {

constexpr size_t kMaxCloudFields = 16;
constexpr size_t kMaxFieldName = 16;
constexpr size_t kMaxChunkLayers = 12;
constexpr uint8_t kCloudFixRowStep = 1;
constexpr uint8_t kCloudFixWidth = 2;

class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  size_t remaining() const { return size_ - pos_; }

  template <typename T>
  T get() {
    static_assert(std::is_arithmetic<T>::value, "numbers only");
    uint8_t b[sizeof(T)] = {};
    const size_t n = std::min(sizeof(T), remaining());
    if (n > 0) std::memcpy(b, data_ + pos_, n);
    pos_ += n;
    T v;
    std::memcpy(&v, b, sizeof(T));  // the host is little-endian (x86, ARM), as the layout
    return v;
  }
  std::string str(size_t max_length) {
    const size_t n = std::min<size_t>({get<uint8_t>(), max_length, remaining()});
    std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return s;
  }
  /// An array: u32 count, then as many elements as both the count and the bytes allow.
  template <typename T>
  std::vector<T> array() {
    const size_t n = std::min<size_t>(get<uint32_t>(), remaining() / sizeof(T));
    std::vector<T> v(n);
    for (T& x : v) x = get<T>();
    return v;
  }
  std::vector<uint8_t> rest() {
    std::vector<uint8_t> v(data_ + pos_, data_ + size_);
    pos_ = size_;
    return v;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

class Writer {
 public:
  template <typename T>
  void put(T v) {
    static_assert(std::is_arithmetic<T>::value, "numbers only");
    uint8_t b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    out.insert(out.end(), b, b + sizeof(T));
  }
  void str(const std::string& s) {
    put<uint8_t>(static_cast<uint8_t>(s.size()));
    out.insert(out.end(), s.begin(), s.end());
  }
  template <typename T, typename A>
  void array(const std::vector<T, A>& v) {
    put<uint32_t>(static_cast<uint32_t>(v.size()));
    for (const T& x : v) put<T>(x);
  }
  std::vector<uint8_t> out;
};

inline sensor_msgs::PointCloud2 readCloud(Reader& r) {
  sensor_msgs::PointCloud2 msg;
  const uint8_t flags = r.get<uint8_t>();
  msg.height = r.get<uint32_t>();
  msg.width = r.get<uint32_t>();
  msg.is_bigendian = r.get<uint8_t>();
  msg.point_step = r.get<uint32_t>();
  msg.row_step = r.get<uint32_t>();
  msg.is_dense = r.get<uint8_t>();
  msg.fields.resize(std::min<size_t>(r.get<uint8_t>(), kMaxCloudFields));
  for (sensor_msgs::PointField& f : msg.fields) {
    f.name = r.str(kMaxFieldName);
    f.offset = r.get<uint32_t>();
    f.datatype = r.get<uint8_t>();
    f.count = r.get<uint32_t>();
  }
  msg.data = r.rest();
  if ((flags & kCloudFixRowStep) && msg.height > 0) {
    msg.row_step =
        static_cast<uint32_t>(std::min<size_t>(msg.data.size() / msg.height, UINT32_MAX));
    msg.data.resize(static_cast<size_t>(msg.row_step) * msg.height);
  }
  if ((flags & kCloudFixWidth) && msg.point_step > 0) msg.width = msg.row_step / msg.point_step;
  return msg;
}

inline std::vector<uint8_t> writeCloud(const sensor_msgs::PointCloud2& msg, uint8_t flags = 0) {
  Writer w;
  w.put<uint8_t>(flags);
  w.put<uint32_t>(msg.height);
  w.put<uint32_t>(msg.width);
  w.put<uint8_t>(msg.is_bigendian);
  w.put<uint32_t>(msg.point_step);
  w.put<uint32_t>(msg.row_step);
  w.put<uint8_t>(msg.is_dense);
  w.put<uint8_t>(static_cast<uint8_t>(msg.fields.size()));
  for (const sensor_msgs::PointField& f : msg.fields) {
    w.str(f.name);
    w.put<uint32_t>(f.offset);
    w.put<uint8_t>(f.datatype);
    w.put<uint32_t>(f.count);
  }
  w.out.insert(w.out.end(), msg.data.begin(), msg.data.end());
  return w.out;
}

inline RasterChunk::Ptr readChunk(Reader& r) {
  auto msg = boost::make_shared<RasterChunk>();
  msg->header.frame_id = "map";
  msg->chunk_x = r.get<int32_t>();
  msg->chunk_y = r.get<int32_t>();
  msg->shift = r.get<int32_t>();
  msg->map_version = r.get<uint64_t>();
  msg->header.stamp.sec = r.get<uint32_t>();
  msg->header.stamp.nsec = r.get<uint32_t>() % 1000000000u;
  msg->layers.resize(std::min<size_t>(r.get<uint8_t>(), kMaxChunkLayers));
  for (ChunkLayer& L : msg->layers) {
    L.z_shift = r.get<int32_t>();
    L.spans_start = r.get<uint64_t>();
    L.values_start = r.get<uint64_t>();
    L.value_count = r.get<uint32_t>();
  }
  msg->spans = r.array<uint32_t>();
  msg->values = r.array<uint8_t>();
  msg->component_count = r.array<uint8_t>();
  msg->components = r.array<float>();
  return msg;
}

inline void writeChunk(Writer& w, const RasterChunk& msg) {
  w.put<int32_t>(msg.chunk_x);
  w.put<int32_t>(msg.chunk_y);
  w.put<int32_t>(msg.shift);
  w.put<uint64_t>(msg.map_version);
  w.put<uint32_t>(msg.header.stamp.sec);
  w.put<uint32_t>(msg.header.stamp.nsec);
  w.put<uint8_t>(static_cast<uint8_t>(msg.layers.size()));
  for (const ChunkLayer& L : msg.layers) {
    w.put<int32_t>(L.z_shift);
    w.put<uint64_t>(L.spans_start);
    w.put<uint64_t>(L.values_start);
    w.put<uint32_t>(L.value_count);
  }
  w.array(msg.spans);
  w.array(msg.values);
  w.array(msg.component_count);
  w.array(msg.components);
}

inline MapIndex::Ptr readIndex(Reader& r) {
  auto msg = boost::make_shared<MapIndex>();
  msg->header.frame_id = "map";
  msg->header.stamp.sec = r.get<uint32_t>();
  msg->header.stamp.nsec = r.get<uint32_t>() % 1000000000u;
  msg->map_directory = r.str(255);
  msg->map_version = r.get<uint64_t>();
  msg->resolution_m = r.get<double>();
  msg->tile_size_cells = r.get<int32_t>();
  msg->origin_x_m = r.get<double>();
  msg->origin_y_m = r.get<double>();
  msg->z_step_m = r.get<double>();
  msg->ll_floor = r.get<double>();
  msg->ll_ceiling = r.get<double>();
  msg->num_layers = r.get<int32_t>();
  msg->z_coarsening_period = r.get<int32_t>();
  msg->chunk_shift = r.get<int32_t>();
  msg->chunk_x = r.array<int32_t>();
  msg->chunk_y = r.array<int32_t>();
  msg->raster_bytes = r.get<uint64_t>();
  msg->min_x_m = r.get<double>();
  msg->min_y_m = r.get<double>();
  msg->max_x_m = r.get<double>();
  msg->max_y_m = r.get<double>();
  return msg;
}

inline void writeIndex(Writer& w, const MapIndex& msg) {
  w.put<uint32_t>(msg.header.stamp.sec);
  w.put<uint32_t>(msg.header.stamp.nsec);
  w.str(msg.map_directory);
  w.put<uint64_t>(msg.map_version);
  w.put<double>(msg.resolution_m);
  w.put<int32_t>(msg.tile_size_cells);
  w.put<double>(msg.origin_x_m);
  w.put<double>(msg.origin_y_m);
  w.put<double>(msg.z_step_m);
  w.put<double>(msg.ll_floor);
  w.put<double>(msg.ll_ceiling);
  w.put<int32_t>(msg.num_layers);
  w.put<int32_t>(msg.z_coarsening_period);
  w.put<int32_t>(msg.chunk_shift);
  w.array(msg.chunk_x);
  w.array(msg.chunk_y);
  w.put<uint64_t>(msg.raster_bytes);
  w.put<double>(msg.min_x_m);
  w.put<double>(msg.min_y_m);
  w.put<double>(msg.max_x_m);
  w.put<double>(msg.max_y_m);
}

}  // namespace fuzz
}  // namespace gmm_localization
