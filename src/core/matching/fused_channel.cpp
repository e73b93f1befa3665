#include "gmm_localization/core/matching/fused_channel.h"

namespace gmm_localization {

Pose6 planarPose(const Pose6& pose) {
  Pose6 p = pose;
  p.z = p.roll = p.pitch = 0.0;
  return p;
}

HillClimbOutcome fusedHillClimb(const ExactScorer& height, const PointList& height_points,
                                const ExactScorer& ground, const PointList& ground_points,
                                const Pose6& start, const HillClimbOptions& options,
                                TaskPool* pool) {
  ClimbObjective f;
  f.full = [&](const Pose6& p) {
    return height.score(height_points, p, pool) + ground.score(ground_points, planarPose(p), pool);
  };
  const size_t n = height_points.size() + ground_points.size();
  PointList coarse_height, coarse_ground;
  if (options.coarse_points > 0 && n >= 2 * options.coarse_points) {
    const size_t h = options.coarse_points * height_points.size() / n;
    coarse_height = thinEvenly(height_points, h);
    coarse_ground = thinEvenly(ground_points, options.coarse_points - h);
    f.coarse = [&](const Pose6& p) {
      return height.score(coarse_height, p, pool) +
             ground.score(coarse_ground, planarPose(p), pool);
    };
  }
  return hillClimb(f, start, options);
}

}  // namespace gmm_localization
