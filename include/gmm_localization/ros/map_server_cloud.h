#pragma once
// The map_cloud visualisation (pure; the map server publishes it as a PointCloud2 in the map
// frame): one point per non-empty cell near the vehicle, for rviz to colour by the number of
// components (the paper's Fig. 3) or by height.

#include <vector>

#include "gmm_localization/core/map/map_geometry.h"
#include "gmm_localization/core/raster/chunk_planner.h"
#include "gmm_localization/core/raster/map_chunk.h"
#include "gmm_localization/ros/cloud_conversion.h"

namespace gmm_localization {
namespace node {

/// For each non-empty cell of `chunks` whose centre lies within radius_m of a centre: a point
/// at (cell centre x, cell centre y, mean of the cell's heaviest component; the lowest mean on
/// a tie), with cloud.intensity = number of components and sigma_m = that component's sigma
/// [m]. Map frame [m]; chunks in the given order, cells row-major within a chunk. No centre:
/// no point.
void buildMapCloud(const std::vector<MapChunkConstPtr>& chunks, const MapGeometry& geometry,
                   const std::vector<PlanCentre>& centres, double radius_m, CloudData& cloud,
                   std::vector<float>& sigma_m);

}  // namespace node
}  // namespace gmm_localization
