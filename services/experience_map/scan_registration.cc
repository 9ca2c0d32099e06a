#include "services/experience_map/scan_registration.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

namespace rslam::experience_map {

namespace {

// The target points in square buckets, for nearest-point queries.
class PointGrid {
 public:
  PointGrid(std::span<const Eigen::Vector2f> points, double bucket_m) : points_(points), bucket_m_(bucket_m) {
    for (size_t i = 0; i < points.size(); ++i) buckets_[Key(Bucket(points[i].x()), Bucket(points[i].y()))].push_back(i);
  }

  // Indices of the points within radius_m of p.
  template <class F>
  void ForEachWithin(const Eigen::Vector2d& p, double radius_m, F&& f) const {
    const int reach = static_cast<int>(std::ceil(radius_m / bucket_m_));
    const int bx = Bucket(p.x()), by = Bucket(p.y());
    const double r2 = radius_m * radius_m;
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const auto it = buckets_.find(Key(bx + dx, by + dy));
        if (it == buckets_.end()) continue;
        for (const size_t i : it->second)
          if ((points_[i].cast<double>() - p).squaredNorm() <= r2) f(i);
      }
  }

  // The nearest point within radius_m of p, or -1.
  int Nearest(const Eigen::Vector2d& p, double radius_m, double& distance_m) const {
    int best = -1;
    double best2 = radius_m * radius_m;
    ForEachWithin(p, radius_m, [&](size_t i) {
      const double d2 = (points_[i].cast<double>() - p).squaredNorm();
      if (d2 <= best2) {
        best2 = d2;
        best = static_cast<int>(i);
      }
    });
    distance_m = std::sqrt(best2);
    return best;
  }

 private:
  int Bucket(double v) const { return static_cast<int>(std::floor(v / bucket_m_)); }
  static int64_t Key(int x, int y) { return (static_cast<int64_t>(x) << 32) ^ static_cast<uint32_t>(y); }

  std::span<const Eigen::Vector2f> points_;
  double bucket_m_;
  std::unordered_map<int64_t, std::vector<size_t>> buckets_;
};

// The unit normal of each target point's local line (principal axis of its neighbours within
// radius_m), or zero where fewer than three points say where the line goes.
std::vector<Eigen::Vector2d> Normals(std::span<const Eigen::Vector2f> points, const PointGrid& grid, double radius_m) {
  std::vector<Eigen::Vector2d> normals(points.size(), Eigen::Vector2d::Zero());
  std::vector<size_t> near;
  for (size_t i = 0; i < points.size(); ++i) {
    near.clear();
    grid.ForEachWithin(points[i].cast<double>(), radius_m, [&near](size_t j) { near.push_back(j); });
    if (near.size() < 3) continue;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const size_t j : near) mean += points[j].cast<double>();
    mean /= static_cast<double>(near.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const size_t j : near) {
      const Eigen::Vector2d d = points[j].cast<double>() - mean;
      scatter += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(scatter);
    normals[i] = eigen.eigenvectors().col(0);  // the smaller eigenvalue's: across the line
  }
  return normals;
}

double Median(std::vector<double>& values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace

double ScanRegistration::weak_share() const {
  return std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(walls()).eigenvalues()[0]);
}

std::optional<ScanRegistration> RegisterScans(std::span<const Eigen::Vector2f> target,
                                              std::span<const Eigen::Vector2f> source, const Pose2D& initial,
                                              const ScanRegistrationOptions& options) {
  if (target.size() < 3 || source.size() < 3) return std::nullopt;
  const PointGrid grid(target, std::max(options.min_pair_m, 2 * options.cell_m));
  const std::vector<Eigen::Vector2d> normals = Normals(target, grid, 2.5 * options.cell_m);

  Pose2D pose = initial;
  double pair_m = options.max_pair_m;
  std::vector<double> distances;
  ScanRegistration result;
  for (int iteration = 0; iteration < options.iterations; ++iteration) {
    const double c = std::cos(pose.theta), s = std::sin(pose.theta);
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    distances.clear();
    for (const Eigen::Vector2f& point : source) {
      const double px = point.x(), py = point.y();
      const Eigen::Vector2d moved(pose.x + c * px - s * py, pose.y + s * px + c * py);
      double distance = 0.0;
      const int nearest = grid.Nearest(moved, pair_m, distance);
      if (nearest < 0 || normals[static_cast<size_t>(nearest)].isZero()) continue;
      const Eigen::Vector2d& n = normals[static_cast<size_t>(nearest)];
      const double r = n.dot(moved - target[static_cast<size_t>(nearest)].cast<double>());
      const Eigen::Vector3d j(n.x(), n.y(), n.dot(Eigen::Vector2d(-s * px - c * py, c * px - s * py)));
      h += j * j.transpose();
      g += j * r;
      distances.push_back(distance);
    }
    if (distances.size() < 3) return std::nullopt;
    result.pairs = static_cast<int>(distances.size());
    result.median_distance_m = Median(distances);
    result.information = h / result.pairs;
    const Eigen::Vector3d step = -(h + 1e-9 * Eigen::Matrix3d::Identity()).lu().solve(g);
    if (!step.allFinite()) return std::nullopt;
    pose = {pose.x + step.x(), pose.y + step.y(), WrapAngle(pose.theta + step.z())};
    pair_m = std::clamp(3 * result.median_distance_m, options.min_pair_m, pair_m);
    if (step.head<2>().norm() < 1e-4 && std::abs(step.z()) < 1e-4) break;
  }
  result.pose = pose;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  int inliers = 0;
  for (const Eigen::Vector2f& point : source) {
    const Eigen::Vector2d moved(pose.x + c * point.x() - s * point.y(), pose.y + s * point.x() + c * point.y());
    double distance = 0.0;
    inliers += grid.Nearest(moved, 2 * options.cell_m, distance) >= 0;
  }
  result.inlier_share = static_cast<double>(inliers) / static_cast<double>(source.size());
  return result;
}

}  // namespace rslam::experience_map
