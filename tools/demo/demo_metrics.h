#pragma once
// The demo's figures of merit, computed against the simulator's ground truth:
//   - coverage: share of the world's free cells the robot could reach (its disc's footprint from
//     the start, robot radius respected) that the occupancy grid marks free;
//   - map precision: share of the cells the grid marks free or occupied whose class agrees with
//     the world within a tolerance (walls are occupied or unknown world cells);
//   - loop-closure precision: share of loop-closing links whose two experiences were created
//     within a distance of each other in ground truth;
//   - absolute trajectory errors (tools/eval/trajectory_alignment.h), each after a 2-D similarity
//     alignment to ground truth: of the final experience map (each experience where the map ends
//     up putting it, against the true pose at the frame it was made, as SLAM benchmarks judge a
//     run's final key-frame trajectory) and of dead-reckoned odometry at the same frames; and of
//     the live path (the map's pose estimate frame by frame, as it was at that frame) and the
//     odometry over every frame.
// The experience map (and the grid built on it) starts at the robot's start position, turned by
// the map's initial facing (the demo's map origin: the pose of the map frame in the world). Pure
// functions of their inputs.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <vector>

#include "rslam/msg/all_messages.h"
#include "tools/demo/demo_monitor.h"
#include "tools/eval/trajectory_alignment.h"
#include "common/math/pose2d.h"
#include "tools/sim/world_map.h"

namespace rslam::demo {

// A loop closure is right when its two experiences were made this close in ground truth.
inline constexpr double kLoopClosureMaxDistanceM = 1.0;

// map_server thresholds on the 0-100 occupancy scale.
inline constexpr int kFreeAtMost = 19;      // free_thresh 0.196
inline constexpr int kOccupiedAtLeast = 66; // occupied_thresh 0.65

// The map frame's pose in the world: its origin at the start position; the robot, facing
// start.theta in the world, faces initial_facing_rad in the map (the experience map's
// exp_initial_em_deg).
Pose2D MapOrigin(const Pose2D& start, double initial_facing_rad);

// Map frame (whose pose in the world is `origin`) to world frame.
Pose2D MapToWorld(const Pose2D& origin, double x, double y);

// The grid's value (0-100, -1 unknown) at a world point, the map frame's pose in the world being
// `map_origin`; -1 outside the grid.
int GridValueAtWorldPoint(const msg::OccupancyGrid& grid, const Pose2D& map_origin, const Eigen::Vector2d& p);

// Whether the world has a free cell (`free`) or a wall (not `free`) within tolerance_m of p (p's own
// cell always counts): how a grid cell marked free or occupied at p is judged.
bool WorldHasNear(const sim::WorldMap& world, const Eigen::Vector2d& p, bool free, double tolerance_m);

struct GridComparison {
  double coverage = 0.0;
  double precision = 0.0;
  uint64_t reachable_cells = 0;  // world cells the robot's footprint can reach
  uint64_t covered_cells = 0;    // ... that the grid marks free
  // The reachable cells not covered, by what the grid says there: unknown (or outside the grid:
  // never seen, or a wall the map put short of where it is), between the free and occupied
  // thresholds, occupied.
  uint64_t missed_unknown_cells = 0;
  uint64_t missed_uncertain_cells = 0;
  uint64_t missed_occupied_cells = 0;
  uint64_t marked_cells = 0;     // grid cells marked free or occupied
  uint64_t agreeing_cells = 0;   // ... that agree with the world
  // The marked cells that disagree: free with no free world cell within the tolerance (where a
  // planner would drive into a wall), occupied with no wall within it.
  uint64_t wrong_free_cells = 0;
  uint64_t wrong_occupied_cells = 0;
};

// The world cells (sorted, iy then ix) the robot's disc can cover when its centre moves from the
// start through free space.
std::vector<Eigen::Vector2i> ReachableFootprint(const sim::WorldMap& world, const Pose2D& start,
                                                double robot_radius_m);

GridComparison CompareGridWithWorld(const sim::WorldMap& world, std::span<const Eigen::Vector2i> reachable,
                                    const Pose2D& map_origin, const msg::OccupancyGrid& grid, double tolerance_m);

struct WrongLoopClosure {
  uint32_t from_id = 0;
  uint32_t to_id = 0;
  double distance_m = 0.0;  // between their ground-truth poses
};

struct LoopClosureCheck {
  uint32_t links = 0;
  uint32_t loop_closures = 0;
  uint32_t verified = 0;                // both ends have a ground-truth pose
  uint32_t correct = 0;                 // ... within the distance
  std::optional<double> precision;      // correct / verified; none without loop closures
  std::optional<double> farthest_m;     // the verified ones' largest distance: the margin to the mark
  std::vector<WrongLoopClosure> wrong;  // the verified ones farther apart than the distance
};

// Ground truth of each experience: the true pose at the frame it was first current.
std::map<uint32_t, Pose2D> ExperienceGroundTruth(const DemoObservations& seen);

// The rigid transform (map frame to world, as MapToWorld takes it) that best overlays the
// experiences on their ground truth (least squares, no scale: the grid is metric). A map's frame
// is fixed by its first experience only; a map that is right in shape but turned as a whole (its
// corrections do not hold the first experience still) is judged by its shape this way. None with
// fewer than two experiences that have ground truth.
std::optional<Pose2D> FitMapToWorld(std::span<const msg::Experience> experiences,
                                         const std::map<uint32_t, Pose2D>& experience_truth);

LoopClosureCheck CheckLoopClosures(std::span<const msg::ExperienceLink> links,
                                   const std::map<uint32_t, Pose2D>& experience_truth, double max_distance_m);

// Dead reckoning of per-frame velocities (frame order), from (0, 0, 0): turn, then drive.
std::vector<FramePose> DeadReckon(std::vector<FrameVelocity> odometry);

// The final experience map as a trajectory: each experience of `map` at the frame it was first
// current, stamped with that frame's ground-truth stamp, in frame order. Experiences without a
// first frame or without ground truth at it are left out.
std::vector<FramePose> ExperienceMapTrajectory(const msg::ExperienceMap& map, const DemoObservations& seen);

// The poses of `trajectory` at the frames of `frames` (matched by frame_seq), in trajectory order.
std::vector<FramePose> AtFrames(std::span<const FramePose> trajectory, std::span<const FramePose> frames);

// ATE after a similarity alignment (stamps matched exactly, within 1 ms); none when fewer than
// two poses pair up or the estimate does not move.
std::optional<eval::TrajectoryError> TrajectoryErrorAgainstTruth(std::span<const FramePose> estimate,
                                                                 std::span<const FramePose> truth);

// Every figure of a run against the truth, as `rslam demo` and `rslam eval map` report them.
struct RunFigures {
  std::optional<Pose2D> map_to_world;           // FitMapToWorld of the final map
  std::optional<GridComparison> grid;           // the final grid placed by that fit (else the start pose)
  std::optional<GridComparison> grid_at_start;  // ... placed by the start pose (map_origin)
  LoopClosureCheck loops;
  std::vector<FramePose> dead_reckoning;        // the odometry over every frame
  std::vector<FramePose> map_trajectory;        // ExperienceMapTrajectory of the final map
  // ATE of the final map and of the odometry at its frames; of the live path and the odometry at
  // every frame.
  std::optional<eval::TrajectoryError> ate, ate_odometry, ate_live, ate_odometry_all;
};
RunFigures JudgeRun(const sim::WorldMap& world, std::span<const Eigen::Vector2i> reachable, const Pose2D& map_origin,
                    const DemoObservations& seen);

// summary.json's figures: coverage, map_precision, frames, templates, experiences, links,
// loop_closures, loop_closure_precision, wrong_loop_closures, ate_m, ate_odometry_m, live_path,
// grid, map_origin, grid_placement, alignment, odometry_alignment.
nlohmann::json FiguresJson(const RunFigures& figures, const DemoObservations& seen, const Pose2D& map_origin,
                           double tolerance_m);

}  // namespace rslam::demo
