#pragma once
// Parameters of the rasterized lookup tables (paper IV-B) and the integer score quantizer.

#include <cmath>
#include <cstdint>
#include <string>

namespace gmm_localization {

struct RasterOptions {
  /// Height of one z bin of the base layer [m]. A bin stores the largest log-likelihood of the
  /// cell's mixture over the bin's z interval, so a point scores as if at its best height
  /// within the bin: the base layer tolerates height errors up to one bin.
  double z_step_m = 0.1;
  /// Log-likelihood floor [nats]: the per-point score of an empty cell, of a cell outside the map,
  /// and of a z far from every mode (no -inf anywhere). Robustifies Eq. 1 against points that
  /// the map cannot explain (moving cars, snow).
  double ll_floor = -6.0;
  /// Largest log-likelihood the 8-bit table represents [nats]: -ln(sigma_min sqrt(2 pi)) for the
  /// map's sigma floor (3 cm gives 2.58). Higher values saturate at 255 (still an upper bound
  /// of every coarser layer, which takes maxima of stored values).
  double ll_ceiling = 2.6;
  /// Number of coarse layers above the base: layer k in 1..num_layers is the max over the
  /// 2^k x 2^k block of base cells starting at each cell (paper Fig. 4/5).
  int num_layers = 6;
  /// Layer k also takes the max over aligned groups of 2^(k / z_coarsening_period) z bins
  /// (integer division), so coarse layers cost less memory; still an upper bound. 0: no z
  /// coarsening (tightest bounds, (num_layers + 1) x the base layer's memory); 1: halve the z
  /// resolution every layer (about 2x the base layer); 2: every other layer (about 3.6x).
  int z_coarsening_period = 2;
  /// Raster chunks are 2^chunk_shift cells square (independent of the map's file tiles).
  int chunk_shift = 7;

  std::string validate() const {
    if (!(z_step_m >= 0.01 && z_step_m <= 2.0)) {
      return "z_step_m=" + std::to_string(z_step_m) + " must be in [0.01, 2]";
    }
    if (!(std::isfinite(ll_floor) && std::isfinite(ll_ceiling) && ll_ceiling > ll_floor + 0.5)) {
      return "ll_floor=" + std::to_string(ll_floor) +
             " and ll_ceiling=" + std::to_string(ll_ceiling) +
             " must be finite with ll_ceiling > ll_floor + 0.5";
    }
    if (num_layers < 0 || num_layers > 10) {
      return "num_layers=" + std::to_string(num_layers) + " must be in [0, 10]";
    }
    if (z_coarsening_period < 0 || z_coarsening_period > 10) {
      return "z_coarsening_period=" + std::to_string(z_coarsening_period) + " must be in [0, 10]";
    }
    if (chunk_shift < 4 || chunk_shift > 10) {
      return "chunk_shift=" + std::to_string(chunk_shift) + " must be in [4, 10]";
    }
    if ((1 << num_layers) > (1 << chunk_shift)) {
      return "num_layers=" + std::to_string(num_layers) + " needs blocks no larger than a chunk (" +
             std::to_string(1 << chunk_shift) + " cells); raise chunk_shift";
    }
    return {};
  }

  int chunkCells() const { return 1 << chunk_shift; }
  /// log2 of the z-bin grouping of layer k.
  int zShift(int layer) const { return z_coarsening_period > 0 ? layer / z_coarsening_period : 0; }
};

/// Maps a log-likelihood to an 8-bit score, rounding UP so that a quantized value is never
/// below the value it stands for: q(ll) = clamp(ceil((ll - floor) / step), 0, 255).
/// The floor maps to 0. Scores of a cloud are integer sums, so ties are exact.
class ScoreQuantizer {
 public:
  explicit ScoreQuantizer(const RasterOptions& o)
      : floor_(o.ll_floor), step_((o.ll_ceiling - o.ll_floor) / 255.0) {}

  uint8_t quantize(double ll) const {
    if (!(ll > floor_)) return 0;  // also catches -inf and NaN
    const double q = std::ceil((ll - floor_) / step_);
    return q >= 255.0 ? 255 : static_cast<uint8_t>(q);
  }
  /// Log-likelihood represented by a quantized value [nats].
  double toLogLikelihood(double q) const { return floor_ + q * step_; }
  /// Log-likelihood of a sum of n quantized per-point scores totalling `sum`.
  double sumToLogLikelihood(int64_t sum, int64_t n) const {
    return floor_ * static_cast<double>(n) + step_ * static_cast<double>(sum);
  }
  double step() const { return step_; }
  double floor() const { return floor_; }

 private:
  double floor_;
  double step_;
};

}  // namespace gmm_localization
