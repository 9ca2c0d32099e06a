#include "services/odometry/boundary_scan.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace rslam::odometry {

BoundaryScan BoundaryScan::FromPoints(std::vector<Eigen::Vector2d> points, double neighbour_max_distance_m) {
  BoundaryScan scan;
  scan.points = std::move(points);
  const std::vector<Eigen::Vector2d>& p = scan.points;
  const size_t n = p.size();
  scan.normals.assign(n, Eigen::Vector2d::Zero());
  scan.ends_line.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const bool prev = i > 0 && (p[i - 1] - p[i]).norm() <= neighbour_max_distance_m;
    const bool next = i + 1 < n && (p[i + 1] - p[i]).norm() <= neighbour_max_distance_m;
    scan.ends_line[i] = !(prev && next);
    const Eigen::Vector2d along = (next ? p[i + 1] : p[i]) - (prev ? p[i - 1] : p[i]);
    if (along.norm() > 1e-9) scan.normals[i] = Eigen::Vector2d(-along.y(), along.x()).normalized();
  }
  return scan;
}

Alignment AlignToScan(const BoundaryScan& reference, std::span<const Eigen::Vector2d> points,
                      const Eigen::Vector3d& guess, const Eigen::Vector3d& prior, const AlignmentOptions& options) {
  Alignment r;
  r.pose = guess;
  if (static_cast<int>(points.size()) < options.min_pairs) return r;
  Eigen::Vector3d& pose = r.pose;
  const Eigen::Vector2d lateral(-std::sin(prior.z()), std::cos(prior.z()));
  const Eigen::Vector2d forward(std::cos(prior.z()), std::sin(prior.z()));
  const double max_pair2 = options.max_pair_distance_m * options.max_pair_distance_m;
  const std::vector<Eigen::Vector2d>& ref = reference.points;
  for (int iteration = 0; iteration < options.iterations; ++iteration) {
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
      for (size_t k = 0; k < ref.size(); ++k) {
        const double d2 = (ref[k] - q).squaredNorm();
        if (d2 < best2) {
          best2 = d2;
          best = k;
          found = true;
        }
      }
      if (!found || reference.ends_line[best]) continue;
      const Eigen::Vector2d& n = reference.normals[best];
      const double e = n.dot(q - ref[best]);
      const Eigen::Vector3d j(n.x(), n.y(), n.dot(Eigen::Vector2d(-s * p.x() - c * p.y(), c * p.x() - s * p.y())));
      const double weight = 1.0 / std::max(p.squaredNorm() * ref[best].squaredNorm(), 0.01);
      h += weight * j * j.transpose();
      g += weight * j * e;
      weights += weight;
      residual2 += weight * e * e;
      ++pairs;
    }
    r.pairs = pairs;
    r.mean_residual2 = weights > 0 ? residual2 / weights : 0.0;
    if (pairs < options.min_pairs ||
        forward.dot(h.topLeftCorner<2, 2>() * forward) / weights < options.min_forward_constraint) {
      r.ok = false;
      return r;
    }
    if (options.lateral_prior > 0) {
      const Eigen::Vector3d j_lateral(lateral.x(), lateral.y(), 0.0);
      const double lateral_offset = lateral.dot(pose.head<2>() - prior.head<2>());
      h += options.lateral_prior * weights * j_lateral * j_lateral.transpose();
      g += options.lateral_prior * weights * lateral_offset * j_lateral;
    }
    if (options.rotation_prior > 0) {
      h(2, 2) += options.rotation_prior * weights;
      g(2) += options.rotation_prior * weights * (pose.z() - prior.z());
    }
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

}  // namespace rslam::odometry
