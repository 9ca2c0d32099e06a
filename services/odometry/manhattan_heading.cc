#include "services/odometry/manhattan_heading.h"

#include <cmath>

namespace rslam::odometry {

namespace {
constexpr double kNeighbourMaxDistanceM = 0.12;  // farther apart: not one boundary line (as floor_odometry)
}  // namespace

ManhattanHeading::ManhattanHeading(ManhattanHeadingConfig config) : config_(std::move(config)) { config_.Validate(); }

std::optional<double> ManhattanHeading::WallDirection(std::span<const Eigen::Vector2d> boundary) const {
  const size_t k = static_cast<size_t>(config_.baseline_points);
  double sum_cos = 0.0, sum_sin = 0.0, length = 0.0;
  for (size_t i = 0; i + k < boundary.size(); ++i) {
    if (boundary[i].norm() > config_.max_range_m || boundary[i + k].norm() > config_.max_range_m) continue;
    bool one_line = true;
    for (size_t j = i; j < i + k && one_line; ++j)
      one_line = (boundary[j + 1] - boundary[j]).norm() <= kNeighbourMaxDistanceM;
    if (!one_line) continue;
    const Eigen::Vector2d d = boundary[i + k] - boundary[i];
    const double l = d.norm();
    if (l <= 0.0) continue;
    const double a = 4.0 * std::atan2(d.y(), d.x());
    sum_cos += l * std::cos(a);
    sum_sin += l * std::sin(a);
    length += l;
  }
  // Overlapping pairs k bins apart count each stretch of wall k times.
  if (length / static_cast<double>(k) < config_.min_wall_m || std::hypot(sum_cos, sum_sin) < config_.min_agreement * length)
    return std::nullopt;
  return std::atan2(sum_sin, sum_cos) / 4.0;
}

double ManhattanHeading::Update(std::span<const Eigen::Vector2d> boundary, double heading) {
  if (!std::isfinite(heading)) throw std::invalid_argument("ManhattanHeading: the heading is not finite");
  const std::optional<double> wall = WallDirection(boundary);
  if (!wall) return 0.0;
  const double direction = heading + *wall;
  if (!axes_) {
    sum_cos_ += std::cos(4.0 * direction);
    sum_sin_ += std::sin(4.0 * direction);
    if (++reference_count_ < config_.reference_frames) return 0.0;
    if (std::hypot(sum_cos_, sum_sin_) >= config_.min_agreement * reference_count_)
      axes_ = std::atan2(sum_sin_, sum_cos_) / 4.0;
    sum_cos_ = sum_sin_ = 0.0;
    reference_count_ = 0;
    return 0.0;
  }
  const double offset = std::remainder(direction - *axes_, M_PI / 2.0);
  if (std::abs(offset) > config_.max_offset_rad) return 0.0;
  return -config_.gain * offset;
}

}  // namespace rslam::odometry
