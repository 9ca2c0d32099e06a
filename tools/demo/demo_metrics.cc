#include "tools/demo/demo_metrics.h"

#include "common/math/angle.h"
#include "tools/eval/trajectory_alignment.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace rslam::demo {

Pose2D MapOrigin(const Pose2D& start, double initial_facing_rad) {
  return {start.x, start.y, WrapAngle(start.theta - initial_facing_rad)};
}

Pose2D MapToWorld(const Pose2D& origin, double x, double y) { return Compose(origin, {x, y, 0.0}); }

int GridValueAtWorldPoint(const msg::OccupancyGrid& grid, const Pose2D& map_origin, const Eigen::Vector2d& p) {
  const Pose2D m = Between(map_origin, {p.x(), p.y(), 0.0});
  const double gx = (m.x - grid.origin_x_m) / grid.resolution_m;
  const double gy = (m.y - grid.origin_y_m) / grid.resolution_m;
  if (!(gx >= 0 && gy >= 0 && gx < grid.width && gy < grid.height)) return -1;
  const size_t i = static_cast<size_t>(gy) * grid.width + static_cast<size_t>(gx);
  return i < grid.cells.size() ? grid.cells[i] : -1;
}

bool WorldHasNear(const sim::WorldMap& world, const Eigen::Vector2d& p, bool free, double tolerance_m) {
  const int reach = static_cast<int>(std::ceil(tolerance_m / world.resolution()));
  const Eigen::Vector2i centre = world.WorldToCell(p);
  for (int dy = -reach; dy <= reach; ++dy)
    for (int dx = -reach; dx <= reach; ++dx) {
      const Eigen::Vector2i c = centre + Eigen::Vector2i(dx, dy);
      if ((world.CellCenter(c) - p).norm() > tolerance_m + 0.5 * world.resolution() && (dx != 0 || dy != 0)) continue;
      if (free ? world.Classify(c) == sim::CellClass::kFree : world.IsWall(c)) return true;
    }
  return false;
}

std::vector<Eigen::Vector2i> ReachableFootprint(const sim::WorldMap& world, const Pose2D& start,
                                                double robot_radius_m) {
  const std::vector<Eigen::Vector2i> centres = world.ReachableFreeCells({start.x, start.y}, robot_radius_m);
  cv::Mat mask = cv::Mat::zeros(world.height(), world.width(), CV_8U);
  for (const auto& c : centres) mask.at<uint8_t>(c.y(), c.x()) = 255;
  const int r = static_cast<int>(std::ceil(robot_radius_m / world.resolution()));
  if (r > 0) cv::dilate(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1}));
  std::vector<Eigen::Vector2i> footprint;
  for (int iy = 0; iy < world.height(); ++iy)
    for (int ix = 0; ix < world.width(); ++ix)
      if (mask.at<uint8_t>(iy, ix) && world.Classify({ix, iy}) == sim::CellClass::kFree) footprint.emplace_back(ix, iy);
  return footprint;
}

GridComparison CompareGridWithWorld(const sim::WorldMap& world, std::span<const Eigen::Vector2i> reachable,
                                    const Pose2D& map_origin, const msg::OccupancyGrid& grid, double tolerance_m) {
  if (grid.cells.size() != static_cast<size_t>(grid.width) * grid.height || !(grid.resolution_m > 0))
    throw std::invalid_argument("occupancy grid: cells do not match width x height, or bad resolution");
  GridComparison out;
  out.reachable_cells = reachable.size();
  for (const auto& cell : reachable) {
    const int v = GridValueAtWorldPoint(grid, map_origin, world.CellCenter(cell));
    if (v < 0)
      ++out.missed_unknown_cells;
    else if (v <= kFreeAtMost)
      ++out.covered_cells;
    else if (v < kOccupiedAtLeast)
      ++out.missed_uncertain_cells;
    else
      ++out.missed_occupied_cells;
  }
  out.coverage = reachable.empty() ? 0.0 : static_cast<double>(out.covered_cells) / reachable.size();

  for (uint32_t gy = 0; gy < grid.height; ++gy) {
    for (uint32_t gx = 0; gx < grid.width; ++gx) {
      const int v = grid.cells[static_cast<size_t>(gy) * grid.width + gx];
      const bool free = v >= 0 && v <= kFreeAtMost;
      const bool occupied = v >= kOccupiedAtLeast;
      if (!free && !occupied) continue;
      ++out.marked_cells;
      const Pose2D w = MapToWorld(map_origin, grid.origin_x_m + (gx + 0.5) * grid.resolution_m,
                                  grid.origin_y_m + (gy + 0.5) * grid.resolution_m);
      const bool agrees = WorldHasNear(world, {w.x, w.y}, free, tolerance_m);
      out.agreeing_cells += agrees;
      if (!agrees) ++(free ? out.wrong_free_cells : out.wrong_occupied_cells);
    }
  }
  out.precision = out.marked_cells == 0 ? 0.0 : static_cast<double>(out.agreeing_cells) / out.marked_cells;
  return out;
}

std::map<uint32_t, Pose2D> ExperienceGroundTruth(const DemoObservations& seen) {
  std::map<uint64_t, Pose2D> truth_by_frame;
  for (const auto& t : seen.ground_truth) truth_by_frame[t.frame_seq] = {t.x, t.y, t.theta};
  std::map<uint32_t, Pose2D> out;
  for (const auto& [id, frame] : seen.experience_first_frame) {
    const auto it = truth_by_frame.find(frame);
    if (it != truth_by_frame.end()) out[id] = it->second;
  }
  return out;
}

std::optional<Pose2D> FitMapToWorld(std::span<const msg::Experience> experiences,
                                         const std::map<uint32_t, Pose2D>& experience_truth) {
  // The SE(2) alignment of `rslam eval trajectory` (Umeyama, no scale), experiences paired by id.
  std::map<uint32_t, eval::StampedPose2D> in_map;
  for (const auto& e : experiences)
    if (experience_truth.count(e.id)) in_map[e.id] = {static_cast<int64_t>(e.id), e.x_m, e.y_m, {}};
  std::vector<eval::StampedPose2D> estimate, truth;
  for (const auto& [id, pose] : in_map) {
    estimate.push_back(pose);
    const Pose2D& w = experience_truth.at(id);
    truth.push_back({static_cast<int64_t>(id), w.x, w.y, {}});
  }
  try {
    const eval::TrajectoryError fit = eval::AlignAndCompare(estimate, truth, false, Duration::zero());
    return Pose2D{fit.translation_x, fit.translation_y, fit.rotation_rad};
  } catch (const std::invalid_argument&) {
    return std::nullopt;  // fewer than two pairs, or all at one point
  }
}

LoopClosureCheck CheckLoopClosures(std::span<const msg::ExperienceLink> links,
                                   const std::map<uint32_t, Pose2D>& experience_truth, double max_distance_m) {
  LoopClosureCheck out;
  out.links = static_cast<uint32_t>(links.size());
  for (const auto& link : links) {
    if (!link.closes_loop) continue;
    ++out.loop_closures;
    const auto a = experience_truth.find(link.from_id), b = experience_truth.find(link.to_id);
    if (a == experience_truth.end() || b == experience_truth.end()) continue;
    ++out.verified;
    const double distance = std::hypot(a->second.x - b->second.x, a->second.y - b->second.y);
    out.farthest_m = std::max(out.farthest_m.value_or(0.0), distance);
    if (distance <= max_distance_m)
      ++out.correct;
    else
      out.wrong.push_back({link.from_id, link.to_id, distance});
  }
  if (out.verified > 0) out.precision = static_cast<double>(out.correct) / out.verified;
  return out;
}

std::vector<FramePose> DeadReckon(std::vector<FrameVelocity> odometry) {
  std::sort(odometry.begin(), odometry.end(),
            [](const FrameVelocity& a, const FrameVelocity& b) { return a.frame_seq < b.frame_seq; });
  std::vector<FramePose> out;
  out.reserve(odometry.size());
  double x = 0, y = 0, theta = 0;
  for (const auto& v : odometry) {
    if (!out.empty() && v.frame_seq == out.back().frame_seq) continue;  // a duplicate
    if (std::isfinite(v.vtrans_mps) && std::isfinite(v.vrot_radps) && std::isfinite(v.dt_s)) {
      theta += v.vrot_radps * v.dt_s;
      x += v.vtrans_mps * v.dt_s * std::cos(theta);
      y += v.vtrans_mps * v.dt_s * std::sin(theta);
    }
    out.push_back({v.frame_seq, v.stamp_ns, x, y, theta});
  }
  return out;
}

std::vector<FramePose> ExperienceMapTrajectory(const msg::ExperienceMap& map, const DemoObservations& seen) {
  std::map<uint64_t, int64_t> stamp_by_frame;
  for (const auto& t : seen.ground_truth) stamp_by_frame[t.frame_seq] = t.stamp_ns;
  std::vector<FramePose> out;
  for (const auto& e : map.experiences) {
    const auto first = seen.experience_first_frame.find(e.id);
    if (first == seen.experience_first_frame.end()) continue;
    const auto stamp = stamp_by_frame.find(first->second);
    if (stamp == stamp_by_frame.end()) continue;
    out.push_back({first->second, stamp->second, e.x_m, e.y_m, e.theta_rad});
  }
  std::sort(out.begin(), out.end(), [](const FramePose& a, const FramePose& b) { return a.frame_seq < b.frame_seq; });
  return out;
}

std::vector<FramePose> AtFrames(std::span<const FramePose> trajectory, std::span<const FramePose> frames) {
  std::set<uint64_t> wanted;
  for (const auto& f : frames) wanted.insert(f.frame_seq);
  std::vector<FramePose> out;
  for (const auto& p : trajectory)
    if (wanted.count(p.frame_seq)) out.push_back(p);
  return out;
}

std::optional<eval::TrajectoryError> TrajectoryErrorAgainstTruth(std::span<const FramePose> estimate,
                                                                 std::span<const FramePose> truth) {
  auto convert = [](std::span<const FramePose> poses) {
    std::vector<FramePose> sorted(poses.begin(), poses.end());
    std::sort(sorted.begin(), sorted.end(), [](const FramePose& a, const FramePose& b) { return a.stamp_ns < b.stamp_ns; });
    std::vector<eval::StampedPose2D> out;
    for (const auto& p : sorted) {
      if (!out.empty() && p.stamp_ns <= out.back().stamp_ns) continue;  // stamps must strictly increase
      out.push_back({p.stamp_ns, p.x, p.y, p.theta});
    }
    return out;
  };
  const auto e = convert(estimate), t = convert(truth);
  try {
    return eval::AlignAndCompare(e, t, /*with_scale=*/true, std::chrono::milliseconds(1));
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
}

RunFigures JudgeRun(const sim::WorldMap& world, std::span<const Eigen::Vector2i> reachable, const Pose2D& map_origin,
                    const DemoObservations& seen) {
  RunFigures f;
  const auto experience_truth = ExperienceGroundTruth(seen);
  // The grid judged where the map's shape puts it (a rigid fit of the experiences to their ground
  // truth) and, stricter, where the start pose alone puts it (any turn of the whole map counts).
  if (seen.map) f.map_to_world = FitMapToWorld(seen.map->experiences, experience_truth);
  if (seen.grid) {
    f.grid_at_start = CompareGridWithWorld(world, reachable, map_origin, *seen.grid, world.resolution());
    f.grid = f.map_to_world ? CompareGridWithWorld(world, reachable, *f.map_to_world, *seen.grid, world.resolution())
                            : f.grid_at_start;
  }
  const std::vector<msg::ExperienceLink> no_links;
  f.loops = CheckLoopClosures(seen.map ? seen.map->links : no_links, experience_truth, kLoopClosureMaxDistanceM);
  f.dead_reckoning = DeadReckon(seen.odometry);
  if (seen.map) f.map_trajectory = ExperienceMapTrajectory(*seen.map, seen);
  f.ate = TrajectoryErrorAgainstTruth(f.map_trajectory, seen.ground_truth);
  f.ate_odometry = TrajectoryErrorAgainstTruth(AtFrames(f.dead_reckoning, f.map_trajectory), seen.ground_truth);
  f.ate_live = TrajectoryErrorAgainstTruth(seen.experience_poses, seen.ground_truth);
  f.ate_odometry_all = TrajectoryErrorAgainstTruth(f.dead_reckoning, seen.ground_truth);
  return f;
}

nlohmann::json FiguresJson(const RunFigures& f, const DemoObservations& seen, const Pose2D& map_origin,
                           double tolerance_m) {
  const auto or_null = [](const auto& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
  const auto ate_of = [](const std::optional<eval::TrajectoryError>& e) {
    return e ? nlohmann::json(e->ate_m) : nlohmann::json(nullptr);
  };
  nlohmann::json j;
  j["coverage"] = f.grid ? nlohmann::json(f.grid->coverage) : nlohmann::json(nullptr);
  j["map_precision"] = f.grid ? nlohmann::json(f.grid->precision) : nlohmann::json(nullptr);
  j["frames"] = seen.ground_truth.size();
  j["templates"] = seen.template_count;
  j["experiences"] = seen.map ? static_cast<uint32_t>(seen.map->experiences.size()) : seen.experience_count;
  j["links"] = f.loops.links;
  j["loop_closures"] = f.loops.loop_closures;
  j["loop_closure_precision"] = or_null(f.loops.precision);
  j["loop_closure_farthest_m"] = or_null(f.loops.farthest_m);
  // Each wrong one with the frame its newer end was first current (about when it was made).
  j["wrong_loop_closures"] = nlohmann::json::array();
  for (const WrongLoopClosure& w : f.loops.wrong) {
    const auto first = seen.experience_first_frame.find(std::max(w.from_id, w.to_id));
    j["wrong_loop_closures"].push_back(
        {{"from_id", w.from_id}, {"to_id", w.to_id}, {"distance_m", w.distance_m},
         {"frame", first != seen.experience_first_frame.end() ? nlohmann::json(first->second) : nlohmann::json()}});
  }
  j["ate_m"] = ate_of(f.ate);
  j["ate_odometry_m"] = ate_of(f.ate_odometry);
  j["live_path"] = {{"ate_m", ate_of(f.ate_live)}, {"ate_odometry_m", ate_of(f.ate_odometry_all)},
                    {"frames", f.ate_live ? f.ate_live->pairs : 0}};
  if (f.grid)
    j["grid"] = {{"reachable_cells", f.grid->reachable_cells},
                 {"covered_cells", f.grid->covered_cells},
                 {"marked_cells", f.grid->marked_cells},
                 {"agreeing_cells", f.grid->agreeing_cells},
                 {"missed_cells", {{"unknown", f.grid->missed_unknown_cells},
                                   {"uncertain", f.grid->missed_uncertain_cells},
                                   {"occupied", f.grid->missed_occupied_cells}}},
                 {"wrong_cells", {{"free", f.grid->wrong_free_cells}, {"occupied", f.grid->wrong_occupied_cells}}},
                 {"tolerance_m", tolerance_m},
                 {"placed_by", f.map_to_world ? "rigid fit of the experiences to ground truth" : "start pose"},
                 {"at_start_pose", {{"coverage", f.grid_at_start->coverage},
                                    {"map_precision", f.grid_at_start->precision}}}};
  // The map frame's pose in the world as the start pose and the map's initial facing put it (the
  // placement of grid.at_start_pose), beside the one the rigid fit finds.
  j["map_origin"] = {{"x_m", map_origin.x}, {"y_m", map_origin.y}, {"theta_rad", map_origin.theta}};
  if (f.map_to_world)
    j["grid_placement"] = {{"x_m", f.map_to_world->x}, {"y_m", f.map_to_world->y},
                           {"theta_rad", f.map_to_world->theta}};
  if (f.ate) j["alignment"] = {{"scale", f.ate->scale}, {"rotation_rad", f.ate->rotation_rad}, {"pairs", f.ate->pairs}};
  if (f.ate_odometry)
    j["odometry_alignment"] = {{"scale", f.ate_odometry->scale}, {"pairs", f.ate_odometry->pairs}};
  return j;
}

}  // namespace rslam::demo
