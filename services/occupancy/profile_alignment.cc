#include "services/occupancy/profile_alignment.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <opencv2/imgproc.hpp>

namespace rslam::occupancy {

namespace {

constexpr size_t kMinPoints = 10;       // fewer obstacle points do not pin a pose down
constexpr double kAngleStepRad = 0.02;  // the search's finest turn step; its finest move step is half a cell
// Ties go to the smaller correction: a candidate pays 0.1 points per (0.2 m)^2 and per (0.1 rad)^2.
constexpr double kTieBreakPoints = 0.1;
constexpr double kTieBreakM = 0.2;
constexpr double kTieBreakRad = 0.1;

// Obstacle points are matched up to here: the configured range, or the grid's reliable range.
double MatchRange(const OccupancyGrid& grid, const ProfileAlignmentConfig& config) {
  return std::min(config.match_range_m, grid.sensor_config().reliable_range_m);
}

// The obstacle points within the match range, in the robot's frame, where the grid puts their
// hits (OccupancyGrid::HitRange).
std::vector<Eigen::Vector2d> MatchedPoints(const OccupancyGrid& grid, const RadialObstacleProfile& profile,
                                           const ProfileAlignmentConfig& config) {
  const double range = MatchRange(grid, config);
  std::vector<Eigen::Vector2d> points;
  profile.ObstaclePoints(points);
  std::erase_if(points, [&](const Eigen::Vector2d& p) { return p.norm() > range; });
  for (Eigen::Vector2d& p : points) p = p.normalized() * grid.HitRange(p.norm());
  return points;
}

// Whether a cell is occupied: in the grid, with more than one hit's evidence.
auto OccupiedIn(const OccupancyGrid& grid) {
  const double occupied = 1.01 * LogOddsFromProbability(grid.sensor_config().hit_probability);
  return [&grid, occupied](CellIndex c) { return grid.Contains(c) && grid.LogOdds(c) > occupied; };
}

bool HasMisplacedShare(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& points, const Pose2D& pose,
                       const ProfileAlignmentConfig& config) {
  if (points.size() < kMinPoints) return false;
  // Seen free: more than two misses' evidence, net.
  const double seen_free = 2.5 * LogOddsFromProbability(grid.sensor_config().miss_probability);
  const auto is_occupied = OccupiedIn(grid);
  const double cos0 = std::cos(pose.theta), sin0 = std::sin(pose.theta);
  size_t misplaced = 0;
  for (const Eigen::Vector2d& p : points) {
    const CellIndex c = grid.CellOf(pose.x + cos0 * p.x() - sin0 * p.y(), pose.y + sin0 * p.x() + cos0 * p.y());
    if (!grid.Contains(c) || grid.LogOdds(c) >= seen_free) continue;
    bool by_obstacle = false;
    for (int dy = -1; dy <= 1 && !by_obstacle; ++dy)
      for (int dx = -1; dx <= 1 && !by_obstacle; ++dx) by_obstacle = is_occupied({c.x + dx, c.y + dy});
    if (!by_obstacle) ++misplaced;
  }
  return static_cast<double>(misplaced) >= config.min_misplaced_share * static_cast<double>(points.size());
}

}  // namespace

bool IsMisplaced(const OccupancyGrid& grid, const RadialObstacleProfile& profile, const Pose2D& pose,
                 const ProfileAlignmentConfig& config) {
  return HasMisplacedShare(grid, MatchedPoints(grid, profile, config), pose, config);
}

std::optional<Pose2D> AlignProfile(const OccupancyGrid& grid, const RadialObstacleProfile& profile,
                                   const Pose2D& pose, const ProfileAlignmentConfig& config) {
  if (config.window_m <= 0) return std::nullopt;
  const std::vector<Eigen::Vector2d> points = MatchedPoints(grid, profile, config);
  if (!HasMisplacedShare(grid, points, pose, config)) return std::nullopt;

  // Likelihood field over the patch the search can reach: exp(-d^2 / 2) of the distance d (cells)
  // to the nearest occupied cell.
  const GridConfig& gc = grid.grid_config();
  const double res = gc.resolution_m;
  const CellIndex centre = grid.CellOf(pose.x, pose.y);
  const int half = static_cast<int>(std::ceil((MatchRange(grid, config) + config.window_m) / res)) + 2;
  const int side = 2 * half + 1, x0 = centre.x - half, y0 = centre.y - half;
  const auto is_occupied = OccupiedIn(grid);
  cv::Mat free_of_obstacles(side, side, CV_8U, cv::Scalar(255));
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x)
      if (is_occupied({x0 + x, y0 + y})) free_of_obstacles.at<uint8_t>(y, x) = 0;
  cv::Mat field;
  cv::distanceTransform(free_of_obstacles, field, cv::DIST_L2, cv::DIST_MASK_5);
  field.forEach<float>([](float& d, const int*) { d = std::exp(-0.5f * d * d); });

  // The pose in patch cells (x0, y0 at 0).
  const double px = (pose.x - gc.origin_x_m) / res - x0, py = (pose.y - gc.origin_y_m) / res - y0;
  std::vector<Eigen::Vector2d> turned(points.size());
  double turned_by = NAN;
  const auto turn = [&](double dtheta) {
    if (dtheta == turned_by) return;
    turned_by = dtheta;
    const double c = std::cos(pose.theta + dtheta), s = std::sin(pose.theta + dtheta);
    for (size_t i = 0; i < points.size(); ++i)
      turned[i] = {px + (c * points[i].x() - s * points[i].y()) / res, py + (s * points[i].x() + c * points[i].y()) / res};
  };
  const auto score_at = [&](double dx, double dy) {  // of the turned points moved by (dx, dy) cells
    double score = 0.0;
    for (const Eigen::Vector2d& t : turned) {
      const int cx = static_cast<int>(std::floor(t.x() + dx)), cy = static_cast<int>(std::floor(t.y() + dy));
      if (cx >= 0 && cy >= 0 && cx < side && cy < side) score += field.at<float>(cy, cx);
    }
    return score;
  };
  turn(0.0);
  const double nominal = score_at(0.0, 0.0);
  double best = nominal, best_dtheta = 0.0, best_dx = 0.0, best_dy = 0.0;  // dx, dy in cells
  bool found = false;
  const double max_cells = config.window_m / res + 1e-9;
  const auto consider = [&](double dtheta, double dx, double dy) {
    if ((dtheta == 0 && dx == 0 && dy == 0) || std::abs(dx) > max_cells || std::abs(dy) > max_cells ||
        std::abs(dtheta) > config.window_rad + 1e-9)
      return;
    turn(dtheta);
    const double moved_m = std::hypot(dx, dy) * res;
    const double score = score_at(dx, dy) - kTieBreakPoints * (moved_m * moved_m / (kTieBreakM * kTieBreakM) +
                                                               dtheta * dtheta / (kTieBreakRad * kTieBreakRad));
    if (score > best) {
      best = score;
      best_dtheta = dtheta, best_dx = dx, best_dy = dy;
      found = true;
    }
  };
  // Whole cells and two turn steps over the window, then half of each around the best.
  const int steps_m = static_cast<int>(std::floor(max_cells));
  const int steps_rad = static_cast<int>(std::lround(config.window_rad / (2 * kAngleStepRad)));
  const double coarse_rad = steps_rad > 0 ? config.window_rad / steps_rad : 0.0;
  for (int a = -steps_rad; a <= steps_rad; ++a)
    for (int iy = -steps_m; iy <= steps_m; ++iy)
      for (int ix = -steps_m; ix <= steps_m; ++ix) consider(a * coarse_rad, ix, iy);
  const double around_theta = best_dtheta, around_x = best_dx, around_y = best_dy;
  for (int a = -1; a <= 1; ++a)
    for (int iy = -1; iy <= 1; ++iy)
      for (int ix = -1; ix <= 1; ++ix)
        consider(around_theta + 0.5 * a * coarse_rad, around_x + 0.5 * ix, around_y + 0.5 * iy);
  if (!found || best - nominal < config.min_gain_points) return std::nullopt;
  return Pose2D{pose.x + best_dx * res, pose.y + best_dy * res, WrapAngle(pose.theta + best_dtheta)};
}

}  // namespace rslam::occupancy
