#pragma once
// Absolute trajectory error of a 2-D trajectory estimate against ground truth.
//
// Poses are associated by stamp: each estimate pose takes the ground-truth pose nearest in time,
// if within max_stamp_gap (0 = exact stamps only). The estimate is then aligned to the truth by
// the least-squares similarity transform of Umeyama (1991), truth ~= s R p + t (rotation,
// translation, scale s; with_scale = false fixes s = 1, an SE(2) alignment for metric
// estimates), and the error is the RMS of the remaining position residuals (ATE, Sturm et al.
// 2012). When both poses of every pair carry a heading, the heading error after applying R is
// reported too.

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "common/time/time.h"

namespace rslam::eval {

struct StampedPose2D {
  int64_t stamp_ns = 0;
  double x = 0.0;
  double y = 0.0;
  std::optional<double> theta;  // radians, when known
};

struct TrajectoryError {
  double ate_m = 0.0;          // RMS position error after alignment
  double mean_error_m = 0.0;
  double max_error_m = 0.0;
  std::size_t pairs = 0;       // associated pose pairs
  std::size_t unmatched = 0;   // estimate poses with no ground truth within the stamp gap
  double scale = 1.0;          // s
  double rotation_rad = 0.0;   // angle of R
  double translation_x = 0.0;  // t
  double translation_y = 0.0;
  std::optional<double> heading_rms_rad;  // when every pair has both headings

  // An estimate position moved by the alignment into the truth's frame: s R p + t.
  Eigen::Vector2d Align(double x, double y) const {
    const double c = std::cos(rotation_rad), s = std::sin(rotation_rad);
    return {scale * (c * x - s * y) + translation_x, scale * (s * x + c * y) + translation_y};
  }
};

inline constexpr Duration kDefaultMaxStampGap = std::chrono::milliseconds(10);

// Throws std::invalid_argument when a trajectory has non-finite values or stamps that do not
// strictly increase, when fewer than 2 pairs associate, or when the associated estimate
// positions are all the same point (no alignment exists).
TrajectoryError AlignAndCompare(std::span<const StampedPose2D> estimate, std::span<const StampedPose2D> truth,
                                bool with_scale, Duration max_stamp_gap = kDefaultMaxStampGap);

}  // namespace rslam::eval
