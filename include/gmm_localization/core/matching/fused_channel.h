#pragma once
// The fused method (after the authors' journal version): the score of a pose is the height
// likelihood of the scan's points in the height map plus the reflectivity likelihood of its
// ground returns (reflectivity_scan.h) in the reflectivity map. The search sums the two
// channels' table values (search_problem.h: the sum of admissible bounds is admissible, so every
// search stays exact); the refinement climbs on the sum of both exact likelihoods, the ground
// returns placed by x, y and heading only (they are levelled and their z is a value, not a
// height: z, roll and pitch are driven by the height points alone).

#include "gmm_localization/core/common/task_pool.h"
#include "gmm_localization/core/common/types.h"
#include "gmm_localization/core/matching/exact_scorer.h"
#include "gmm_localization/core/matching/hill_climb.h"
#include "gmm_localization/core/raster/chunk_map.h"

namespace gmm_localization {

/// The fused method's second channel of a match (MatchRequest::fused).
struct FusedChannel {
  /// The reflectivity layer, rasterized with the height map's cells, chunks, layers and score
  /// quantization (channelCompatibility in search_problem.h).
  const ChunkMap* map = nullptr;
  /// The scan's ground returns, levelled, value as z (reflectivityPoints).
  PointList points;
};

/// The pose the ground returns are placed at: `pose`'s x, y and heading (z, roll, pitch 0).
Pose6 planarPose(const Pose6& pose);

/// Hill climb (hill_climb.h) on height.score(height_points, pose) +
/// ground.score(ground_points, planarPose(pose)); its coarse stage thins both sets in
/// proportion to their sizes.
HillClimbOutcome fusedHillClimb(const ExactScorer& height, const PointList& height_points,
                                const ExactScorer& ground, const PointList& ground_points,
                                const Pose6& start, const HillClimbOptions& options,
                                TaskPool* pool = nullptr);

}  // namespace gmm_localization
