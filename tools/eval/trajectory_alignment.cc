#include "tools/eval/trajectory_alignment.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/math/angle.h"

namespace rslam::eval {

namespace {

void RequireValid(std::span<const StampedPose2D> poses, const char* which) {
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const StampedPose2D& p = poses[k];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || (p.theta && !std::isfinite(*p.theta))) {
      throw std::invalid_argument(std::string(which) + " pose " + std::to_string(k) + " has a non-finite value");
    }
    if (k > 0 && p.stamp_ns <= poses[k - 1].stamp_ns) {
      throw std::invalid_argument(std::string(which) + " stamps must strictly increase; pose " + std::to_string(k) +
                                  " (" + std::to_string(p.stamp_ns) + " ns) does not");
    }
  }
}

}  // namespace

TrajectoryError AlignAndCompare(std::span<const StampedPose2D> estimate, std::span<const StampedPose2D> truth,
                                bool with_scale, Duration max_stamp_gap) {
  RequireValid(estimate, "estimate");
  RequireValid(truth, "ground truth");
  if (max_stamp_gap.count() < 0) throw std::invalid_argument("max_stamp_gap must be >= 0");

  // Association: nearest ground-truth stamp (truth is sorted), within the gap.
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  TrajectoryError result;
  for (std::size_t e = 0; e < estimate.size(); ++e) {
    const int64_t stamp = estimate[e].stamp_ns;
    const auto after = std::lower_bound(truth.begin(), truth.end(), stamp,
                                        [](const StampedPose2D& p, int64_t s) { return p.stamp_ns < s; });
    std::size_t best = truth.size();
    int64_t best_gap = 0;
    if (after != truth.end()) {
      best = static_cast<std::size_t>(after - truth.begin());
      best_gap = after->stamp_ns - stamp;
    }
    if (after != truth.begin()) {
      const auto before = after - 1;
      if (best == truth.size() || stamp - before->stamp_ns < best_gap) {
        best = static_cast<std::size_t>(before - truth.begin());
        best_gap = stamp - before->stamp_ns;
      }
    }
    if (best != truth.size() && best_gap <= max_stamp_gap.count()) {
      pairs.emplace_back(e, best);
    } else {
      ++result.unmatched;
    }
  }
  if (pairs.size() < 2) {
    throw std::invalid_argument("only " + std::to_string(pairs.size()) +
                                " estimate poses have a ground-truth pose within the stamp gap; need at least 2");
  }

  const auto n = static_cast<Eigen::Index>(pairs.size());
  Eigen::Matrix2Xd source(2, n), target(2, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const StampedPose2D& e = estimate[pairs[static_cast<std::size_t>(k)].first];
    const StampedPose2D& g = truth[pairs[static_cast<std::size_t>(k)].second];
    source.col(k) << e.x, e.y;
    target.col(k) << g.x, g.y;
  }
  const Eigen::Vector2d source_mean = source.rowwise().mean();
  if ((source.colwise() - source_mean).squaredNorm() <= 1e-18 * std::max(1.0, source_mean.squaredNorm())) {
    throw std::invalid_argument("the associated estimate positions are all one point; no alignment exists");
  }
  // Umeyama's least-squares similarity (Umeyama 1991, eqs. 40-42) in 2-D closed form: with the
  // centred points p' and q', the best rotation angle is atan2(sum p' x q', sum p' . q') and the
  // best scale |(sum p'.q', sum p' x q')| / sum |p'|^2.
  const Eigen::Vector2d target_mean = target.rowwise().mean();
  const Eigen::Matrix2Xd centred_source = source.colwise() - source_mean;
  const Eigen::Matrix2Xd centred_target = target.colwise() - target_mean;
  const double dot = (centred_source.array() * centred_target.array()).sum();
  const double cross = (centred_source.row(0).array() * centred_target.row(1).array() -
                        centred_source.row(1).array() * centred_target.row(0).array()).sum();
  const double source_spread = centred_source.squaredNorm();
  result.rotation_rad = std::atan2(cross, dot);
  result.scale = with_scale ? std::hypot(dot, cross) / source_spread : 1.0;
  const Eigen::Matrix2d scaled_rotation = result.scale * Eigen::Rotation2Dd(result.rotation_rad).toRotationMatrix();
  const Eigen::Vector2d translation = target_mean - scaled_rotation * source_mean;
  result.translation_x = translation.x();
  result.translation_y = translation.y();
  result.pairs = pairs.size();

  double sum_sq = 0.0, sum = 0.0, heading_sum_sq = 0.0;
  bool all_headings = true;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double error = (scaled_rotation * source.col(k) + translation - target.col(k)).norm();
    sum_sq += error * error;
    sum += error;
    result.max_error_m = std::max(result.max_error_m, error);
    const StampedPose2D& e = estimate[pairs[static_cast<std::size_t>(k)].first];
    const StampedPose2D& g = truth[pairs[static_cast<std::size_t>(k)].second];
    if (e.theta && g.theta) {
      const double heading_error = WrapAngle(*g.theta - (*e.theta + result.rotation_rad));
      heading_sum_sq += heading_error * heading_error;
    } else {
      all_headings = false;
    }
  }
  result.ate_m = std::sqrt(sum_sq / static_cast<double>(n));
  result.mean_error_m = sum / static_cast<double>(n);
  if (all_headings) result.heading_rms_rad = std::sqrt(heading_sum_sq / static_cast<double>(n));
  return result;
}

}  // namespace rslam::eval
