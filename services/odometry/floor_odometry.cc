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
// unless the points insist (weight per pair, as if that many extra pairs had a lateral normal);
// the rotation prior (the column-shift rotation, good to about 2%) weighs a tenth of a pair per
// radian-metre.
constexpr double kLateralPriorPerPair = 10.0;
constexpr double kRotationPriorPerPair = 0.1;
// Key points farther apart than this are not neighbours on one boundary line.
constexpr double kNeighbourMaxDistanceM = 0.12;

}  // namespace

FloorOdometry::FloorOdometry(FloorOdometryConfig config) : config_(std::move(config)) { config_.Validate(); }

void FloorOdometry::Reset() {
  has_key_ = false;
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

PlanarMotion FloorOdometry::Update(std::span<const Eigen::Vector2d> boundary, const PlanarMotion& prior) {
  if (!std::isfinite(prior.dx) || !std::isfinite(prior.dy) || !std::isfinite(prior.dtheta))
    throw std::invalid_argument("FloorOdometry: the prior motion is not finite");
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
    return out;
  }
  const Eigen::Vector3d previous = key_to_robot_;
  const Eigen::Vector3d predicted = Compose(previous, prior.dx, prior.dy, prior.dtheta);
  Eigen::Vector3d pose = predicted;
  bool registered = static_cast<int>(points.size()) >= config_.min_points;
  const Eigen::Vector2d lateral(-std::sin(predicted.z()), std::cos(predicted.z()));
  const Eigen::Vector2d forward(std::cos(predicted.z()), std::sin(predicted.z()));
  const double max_pair2 = config_.max_pair_distance_m * config_.max_pair_distance_m;
  for (int iteration = 0; registered && iteration < config_.iterations; ++iteration) {
    const double c = std::cos(pose.z()), s = std::sin(pose.z());
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    int pairs = 0;
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
      h += j * j.transpose();
      g += j * e;
      ++pairs;
    }
    out.pairs = pairs;
    if (pairs < config_.min_points ||
        forward.dot(h.topLeftCorner<2, 2>() * forward) / pairs < config_.min_constraint) {
      registered = false;
      break;
    }
    const Eigen::Vector3d j_lateral(lateral.x(), lateral.y(), 0.0);
    const double lateral_offset = lateral.dot(pose.head<2>() - predicted.head<2>());
    h += kLateralPriorPerPair * pairs * j_lateral * j_lateral.transpose();
    g += kLateralPriorPerPair * pairs * lateral_offset * j_lateral;
    h(2, 2) += kRotationPriorPerPair * pairs;
    g(2) += kRotationPriorPerPair * pairs * (pose.z() - predicted.z());
    const Eigen::Vector3d step = h.ldlt().solve(-g);
    if (!step.allFinite()) {
      registered = false;
      break;
    }
    pose += step;
    if (step.head<2>().norm() < 1e-6 && std::abs(step.z()) < 1e-7) break;
  }
  if (registered) {
    const int pairs = out.pairs;
    out = Between(previous, pose);
    out.measured = true;
    out.pairs = pairs;
    key_to_robot_ = pose;
  } else {
    key_to_robot_ = predicted;
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
