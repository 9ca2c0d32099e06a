#include "services/odometry/floor_odometry.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

namespace rslam::odometry {

namespace {

// Pose (x, y, theta) composed with a motion expressed in that pose's frame.
Eigen::Vector3d Compose(const Eigen::Vector3d& pose, double dx, double dy, double dtheta) {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  return {pose.x() + c * dx - s * dy, pose.y() + s * dx + c * dy, pose.z() + dtheta};
}

// The motion from pose a to pose b, in a's frame.
PlanarMotion Between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  const double ex = b.x() - a.x(), ey = b.y() - a.y();
  PlanarMotion m;
  m.dx = c * ex + s * ey;
  m.dy = -s * ex + c * ey;
  m.dtheta = std::remainder(b.z() - a.z(), 2.0 * M_PI);
  return m;
}

// The robot cannot move sideways, so the registration keeps the lateral offset of the prediction
// unless the points insist (weight: as if every pair had a lateral normal ten times over). The
// turn stays near the seed's (the column-shift rotation is unbiased, only quantised to a pixel;
// the boundary points, quantised to image rows, pull turns short): on a recorded demo path with
// the true turn as prior, the summed turn came out 0.3% short at 3 (1.7% at 0.1, 0.7% at 1).
constexpr double kLateralPriorPerPair = 10.0;
constexpr double kRotationPriorPerPair = 3.0;
// Key points farther apart than this are not neighbours on one boundary line.
constexpr double kNeighbourMaxDistanceM = 0.12;

}  // namespace

FloorOdometry::FloorOdometry(FloorOdometryConfig config) : config_(std::move(config)) { config_.Validate(); }

void FloorOdometry::Reset() {
  has_key_ = false;
  last_registered_ = false;
  last_moving_dx_ = 0.0;
  frames_since_moving_dx_ = -1;
  key_points_.clear();
  key_normals_.clear();
  key_to_robot_.setZero();
}

void FloorOdometry::MakeKeyFrame(std::vector<Eigen::Vector2d>&& points) {
  key_points_ = std::move(points);
  key_normals_.resize(key_points_.size());
  const size_t n = key_points_.size();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& p = key_points_[i];
    const bool prev = i > 0 && (key_points_[i - 1] - p).norm() <= kNeighbourMaxDistanceM;
    const bool next = i + 1 < n && (key_points_[i + 1] - p).norm() <= kNeighbourMaxDistanceM;
    Eigen::Vector2d along = Eigen::Vector2d::Zero();
    if (prev || next) along = (next ? key_points_[i + 1] : p) - (prev ? key_points_[i - 1] : p);
    // A lone point: point-to-point along the viewing ray.
    key_normals_[i] = along.norm() > 1e-9 ? Eigen::Vector2d(-along.y(), along.x()).normalized()
                                          : Eigen::Vector2d(-p.normalized());
  }
  key_to_robot_.setZero();
  has_key_ = true;
}

FloorOdometry::Registration FloorOdometry::Register(const std::vector<Eigen::Vector2d>& points,
                                                    const Eigen::Vector3d& predicted) const {
  Registration r;
  r.pose = predicted;
  if (static_cast<int>(points.size()) < config_.min_points) return r;
  Eigen::Vector3d& pose = r.pose;
  const Eigen::Vector2d lateral(-std::sin(predicted.z()), std::cos(predicted.z()));
  const Eigen::Vector2d forward(std::cos(predicted.z()), std::sin(predicted.z()));
  const double max_pair2 = config_.max_pair_distance_m * config_.max_pair_distance_m;
  for (int iteration = 0; iteration < config_.iterations; ++iteration) {
    const double c = std::cos(pose.z()), s = std::sin(pose.z());
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    int pairs = 0;
    double weights = 0.0, residual2 = 0.0;
    for (const Eigen::Vector2d& p : points) {
      const Eigen::Vector2d q(pose.x() + c * p.x() - s * p.y(), pose.y() + s * p.x() + c * p.y());
      size_t best = 0;
      double best2 = max_pair2;
      bool found = false;
      for (size_t k = 0; k < key_points_.size(); ++k) {
        const double d2 = (key_points_[k] - q).squaredNorm();
        if (d2 < best2) {
          best2 = d2;
          best = k;
          found = true;
        }
      }
      if (!found) continue;
      const Eigen::Vector2d& n = key_normals_[best];
      const double e = n.dot(q - key_points_[best]);
      const Eigen::Vector3d j(n.x(), n.y(), n.dot(Eigen::Vector2d(-s * p.x() - c * p.y(), c * p.x() - s * p.y())));
      // One image row spans a floor distance growing with the square of the range: weigh by the
      // inverse variance, relative to a point 1 m away.
      const double weight = 1.0 / std::max(p.squaredNorm() * key_points_[best].squaredNorm(), 0.01);
      h += weight * j * j.transpose();
      g += weight * j * e;
      weights += weight;
      residual2 += weight * e * e;
      ++pairs;
    }
    r.pairs = pairs;
    r.mean_residual2 = weights > 0 ? residual2 / weights : 0.0;
    if (pairs < config_.min_points ||
        forward.dot(h.topLeftCorner<2, 2>() * forward) / weights < config_.min_constraint) {
      r.ok = false;
      return r;
    }
    const Eigen::Vector3d j_lateral(lateral.x(), lateral.y(), 0.0);
    const double lateral_offset = lateral.dot(pose.head<2>() - predicted.head<2>());
    h += kLateralPriorPerPair * weights * j_lateral * j_lateral.transpose();
    g += kLateralPriorPerPair * weights * lateral_offset * j_lateral;
    h(2, 2) += kRotationPriorPerPair * weights;
    g(2) += kRotationPriorPerPair * weights * (pose.z() - predicted.z());
    const Eigen::Vector3d step = h.ldlt().solve(-g);
    if (!step.allFinite()) {
      r.ok = false;
      return r;
    }
    pose += step;
    r.ok = true;
    if (step.head<2>().norm() < 1e-6 && std::abs(step.z()) < 1e-7) break;
  }
  return r;
}

PlanarMotion FloorOdometry::Update(std::span<const Eigen::Vector2d> boundary, const PlanarMotion& given_prior) {
  if (!std::isfinite(given_prior.dx) || !std::isfinite(given_prior.dy) || !std::isfinite(given_prior.dtheta))
    throw std::invalid_argument("FloorOdometry: the prior motion is not finite");
  const bool moving = given_prior.dx != 0.0;
  PlanarMotion prior = given_prior;
  if (frames_since_moving_dx_ >= 0) ++frames_since_moving_dx_;
  if (moving && frames_since_moving_dx_ >= 0 && frames_since_moving_dx_ <= config_.coast_frames)
    prior.dx = last_moving_dx_;
  std::vector<Eigen::Vector2d> points;
  points.reserve(boundary.size());
  for (const Eigen::Vector2d& p : boundary) {
    if (!p.allFinite()) throw std::invalid_argument("FloorOdometry: a boundary point is not finite");
    if (p.norm() <= config_.max_range_m) points.push_back(p);
  }
  PlanarMotion out = prior;
  out.measured = false;
  out.pairs = 0;
  if (!has_key_ || static_cast<int>(key_points_.size()) < config_.min_points) {
    MakeKeyFrame(std::move(points));
    last_registered_ = false;
    return out;
  }
  const Eigen::Vector3d previous = key_to_robot_;
  // Seeds: the prior; the last registered motion (constant velocity), right when the column
  // profiles are fooled (repeated texture can fake a fast turn during a straight move); and the
  // last registered forward step with the prior's turn, right when the profiles miss that the
  // robot drives (a plain wall ahead looks the same from a little closer).
  std::vector<PlanarMotion> seeds = {prior};
  if (last_registered_) seeds.push_back(last_motion_);
  if (frames_since_moving_dx_ >= 0 && prior.dx != last_moving_dx_) {  // a seed may be any age
    PlanarMotion driving_on = prior;
    driving_on.dx = last_moving_dx_;
    seeds.push_back(driving_on);
  }
  Registration best;
  for (const PlanarMotion& seed : seeds) {
    const Registration r = Register(points, Compose(previous, seed.dx, seed.dy, seed.dtheta));
    if (!r.ok) continue;
    // The closer fit wins, unless it pairs up clearly fewer points (a wrong seed can still
    // settle where a few points happen to fit).
    const bool better_fit = r.mean_residual2 < best.mean_residual2 && r.pairs * 5 >= best.pairs * 4;
    const bool many_more_pairs = best.pairs * 5 < r.pairs * 4;
    if (!best.ok || better_fit || many_more_pairs) best = r;
  }
  out.pairs = best.pairs;
  const bool registered = best.ok;
  last_registered_ = registered;
  if (registered) {
    out = Between(previous, best.pose);
    out.measured = true;
    out.pairs = best.pairs;
    key_to_robot_ = best.pose;
    last_motion_ = out;
    if (moving) {
      last_moving_dx_ = out.dx;
      frames_since_moving_dx_ = 0;
    }
  } else {
    key_to_robot_ = Compose(previous, prior.dx, prior.dy, prior.dtheta);
  }
  if (!registered || key_to_robot_.head<2>().norm() >= config_.keyframe_translation_m ||
      std::abs(key_to_robot_.z()) >= config_.keyframe_rotation_rad) {
    const int pairs = out.pairs;
    MakeKeyFrame(std::move(points));
    out.pairs = pairs;
  }
  return out;
}

}  // namespace rslam::odometry
