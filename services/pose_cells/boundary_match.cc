#include "services/pose_cells/boundary_match.h"

#include "common/math/angle.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace rslam::pose_cells {

namespace {

constexpr std::array<double, 5> kForwardSeedsM = {-0.8, -0.4, 0.0, 0.4, 0.8};
constexpr int kIterations = 20;
constexpr double kGateMedians = 2.5;
constexpr double kMinGateM = 0.05;

struct Pairing {
  std::vector<Eigen::Vector2d> moved;   // current points under the pose
  std::vector<Eigen::Vector2d> nearest;  // their nearest stored points
  std::vector<double> distance;
  double median = 0.0;
};

Eigen::Vector2d Apply(const Eigen::Vector3d& pose, const Eigen::Vector2d& p) {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  return {c * p.x() - s * p.y() + pose.x(), s * p.x() + c * p.y() + pose.y()};
}

void Pair(const std::vector<Eigen::Vector2d>& stored, const std::vector<Eigen::Vector2d>& current,
          const Eigen::Vector3d& pose, Pairing& out) {
  out.moved.clear();
  out.nearest.clear();
  out.distance.clear();
  for (const Eigen::Vector2d& p : current) {
    const Eigen::Vector2d q = Apply(pose, p);
    double best = std::numeric_limits<double>::max();
    const Eigen::Vector2d* nearest = &stored.front();
    for (const Eigen::Vector2d& r : stored) {
      const double d2 = (r - q).squaredNorm();
      if (d2 < best) {
        best = d2;
        nearest = &r;
      }
    }
    out.moved.push_back(q);
    out.nearest.push_back(*nearest);
    out.distance.push_back(std::sqrt(best));
  }
  std::vector<double> sorted = out.distance;
  const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), mid, sorted.end());
  out.median = *mid;
}

// The rigid motion that best takes the gated moved points onto their partners, composed onto
// pose. Returns false when fewer than three pairs pass the gate.
bool Update(const Pairing& pairing, Eigen::Vector3d& pose) {
  const double gate = std::max(kGateMedians * pairing.median, kMinGateM);
  Eigen::Vector2d mean_a = Eigen::Vector2d::Zero(), mean_b = Eigen::Vector2d::Zero();
  int n = 0;
  for (size_t k = 0; k < pairing.moved.size(); ++k) {
    if (pairing.distance[k] > gate) continue;
    mean_a += pairing.moved[k];
    mean_b += pairing.nearest[k];
    ++n;
  }
  if (n < 3) return false;
  mean_a /= n;
  mean_b /= n;
  double dot = 0.0, cross = 0.0;
  for (size_t k = 0; k < pairing.moved.size(); ++k) {
    if (pairing.distance[k] > gate) continue;
    const Eigen::Vector2d u = pairing.moved[k] - mean_a, v = pairing.nearest[k] - mean_b;
    dot += u.dot(v);
    cross += u.x() * v.y() - u.y() * v.x();
  }
  const double turn = std::atan2(cross, dot);
  // New pose = R(turn) (pose) + (mean_b - R(turn) mean_a).
  const Eigen::Vector3d step(0.0, 0.0, turn);
  const Eigen::Vector2d shift = mean_b - Apply(step, mean_a);
  const Eigen::Vector2d position = Apply(step, pose.head<2>()) + shift;
  pose = {position.x(), position.y(), WrapAngle(pose.z() + turn)};
  return true;
}

}  // namespace

BoundaryMatch RegisterBoundaries(std::span<const Eigen::Vector2f> stored, std::span<const Eigen::Vector2f> current) {
  if (stored.empty() || current.empty()) throw std::invalid_argument("RegisterBoundaries needs two non-empty scans");
  std::vector<Eigen::Vector2d> a, b;
  for (const Eigen::Vector2f& p : stored) a.push_back(p.cast<double>());
  for (const Eigen::Vector2f& p : current) b.push_back(p.cast<double>());
  BoundaryMatch best;
  best.median_residual_m = std::numeric_limits<double>::max();
  Pairing pairing;
  static_assert(kForwardSeedsM.size() == std::tuple_size_v<decltype(best.ends)>);
  for (size_t k = 0; k < kForwardSeedsM.size(); ++k) {
    Eigen::Vector3d pose(kForwardSeedsM[k], 0.0, 0.0);
    for (int i = 0; i < kIterations; ++i) {
      Pair(a, b, pose, pairing);
      if (!Update(pairing, pose)) break;
    }
    Pair(a, b, pose, pairing);
    best.ends[k] = {pose, pairing.median};
    if (pairing.median < best.median_residual_m) {
      best.median_residual_m = pairing.median;
      best.pose = pose;
    }
  }
  return best;
}

Eigen::Vector2d BoundaryMatch::NearestAlike(const Eigen::Vector2d& guess, double alike) const {
  Eigen::Vector2d nearest = pose.head<2>();
  for (const End& end : ends) {
    if (end.median_residual_m <= alike * median_residual_m &&
        (end.pose.head<2>() - guess).norm() < (nearest - guess).norm())
      nearest = end.pose.head<2>();
  }
  return nearest;
}

}  // namespace rslam::pose_cells
