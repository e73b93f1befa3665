#pragma once
// The sensor rig: HDL-32E mounts on the roof (extrinsics base_link -> velodyne_N), their
// revolution phases, and the ego vehicle's body (rays that hit it are dropped, as a
// self-filter would). ExtrinsicErrorConfig and perturbedRig() model a vehicle whose calibration
// is slightly wrong: the true mounts (used for ray casting) differ from the nominal ones (what
// the consumer is told in /tf_static and what merging and deskewing use).

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gmm_localization/core/common/result.h"

namespace gmm_localization {
namespace sim {

struct SensorMount {
  std::string frame_id;              ///< e.g. "velodyne_0"
  Eigen::Isometry3d base_to_sensor;  ///< pose of the sensor in base_link
  /// Start of revolution 0 [s]: revolution k of this sensor spans
  /// [phase + k T, phase + (k + 1) T), T = 1 / rotation rate; phase in [0, T).
  double phase_s = 0.0;
};

struct RigConfig {
  std::vector<SensorMount> sensors;
  /// Ego body in base_link as axis-aligned boxes [m]: the cabin under the roof sensors and the
  /// lower hood-to-trunk body.
  std::vector<Eigen::AlignedBox3d> ego_boxes{
      Eigen::AlignedBox3d(Eigen::Vector3d(-1.35, -0.95, 0.2), Eigen::Vector3d(0.95, 0.95, 1.80)),
      Eigen::AlignedBox3d(Eigen::Vector3d(-2.45, -0.98, 0.2), Eigen::Vector3d(2.45, 0.98, 1.10))};

  /// Four sensors at the roof corners (+-x_m, +-y_m, z_m), each yawed toward its corner
  /// (45, -45, 135, -135 deg) and tilted outward by tilt_deg; phases 0, 0.23, 0.51, 0.74 of the
  /// period `period_s` (unsynchronised). Order: front-left, front-right, rear-left, rear-right.
  static RigConfig fourRoofCorners(double x_m = 1.1, double y_m = 0.72, double z_m = 1.95,
                                   double tilt_deg = 5.0, double period_s = 0.1);
  /// One sensor on the roof centre (for validation against a single real HDL-32E).
  static RigConfig single(double z_m = 1.95, double tilt_deg = 0.0);

  Status validate(double period_s) const;
};

enum class ExtrinsicErrorMode { kNone, kRealistic };

/// "none" or "realistic"; anything else is a failure naming the value.
Result<ExtrinsicErrorMode> parseExtrinsicErrorMode(const std::string& name);

/// Per-sensor calibration error: each mount's true pose differs from the nominal one by a
/// translation of random direction and a rotation about a random axis (both uniform on the
/// sphere), with magnitudes uniform in [min, max]. Deterministic for (seed, sensor index).
/// Defaults: the band of a careful but not perfect target/motion-based calibration.
struct ExtrinsicErrorConfig {
  ExtrinsicErrorMode mode = ExtrinsicErrorMode::kNone;
  double translation_min_m = 0.01;
  double translation_max_m = 0.02;
  double rotation_min_deg = 0.1;
  double rotation_max_deg = 0.2;
  uint64_t seed = 1;
  /// 0 <= min <= max, translation max <= 0.5 m, rotation max <= 10 deg.
  Status validate() const;
};

/// The true rig: sensor k's mount becomes (R_err R_nominal, t_nominal + dt) with dt and the
/// rotation R_err (about the sensor's own origin, axes of base_link) drawn as described above.
/// Mode none returns `nominal` unchanged. Frames, phases and ego boxes are kept.
RigConfig perturbedRig(const RigConfig& nominal, const ExtrinsicErrorConfig& config);

/// How `truth` differs from `nominal` (both base_link -> sensor), in base_link.
struct MountError {
  Eigen::Vector3d translation_m;  ///< t_true - t_nominal
  Eigen::Vector3d rotation_rad;   ///< rotation vector (axis x angle) of R_true R_nominal^T
};
MountError mountError(const SensorMount& nominal, const SensorMount& truth);

}  // namespace sim
}  // namespace gmm_localization
