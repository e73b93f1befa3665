#pragma once
// Core MapChunk <-> gmm_localization/RasterChunk message. fromMsg shares the message's memory
// (no copy): the returned chunk keeps the message alive, which is what makes ConstPtr
// publishing inside one nodelet manager zero-copy.

#include <string>

#include <ros/time.h>

#include "gmm_localization/RasterChunk.h"
#include "gmm_localization/core/common/result.h"
#include "gmm_localization/core/raster/map_chunk.h"

namespace gmm_localization {
namespace node {

/// Fills msg from chunk (one copy of the tables).
void toMsg(const MapChunk& chunk, uint64_t map_version, const std::string& frame_id,
           const ros::Time& stamp, RasterChunk& msg);

/// Wraps a received chunk message. Fails, naming the problem, when its sizes are inconsistent
/// or any field is out of range: shift outside [4, 10], z_shift outside [0, 16], a span's z bins
/// beyond +-2^24, a component beyond the map format's physical bounds (map_format.h). Every
/// integer is range-checked before arithmetic, so no input causes signed overflow.
Result<MapChunkConstPtr> fromMsg(const RasterChunk::ConstPtr& msg);

}  // namespace node
}  // namespace gmm_localization
