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
/// beyond +-2^24, a component outside what the map format holds (map_format.h): weight, mean and
/// sigma finite, weight in (0, 1], |mean| <= kMaxMapHeightM, sigma in [1e-4 m (the format's
/// smallest), kMaxComponentSigmaM]; the reason names the cell, the component and the field.
/// Every integer is range-checked before arithmetic, so no input causes signed overflow, and
/// every accepted mixture has finite 1 / sigma and log-likelihoods (never NaN).
Result<MapChunkConstPtr> fromMsg(const RasterChunk::ConstPtr& msg);

}  // namespace node
}  // namespace gmm_localization
