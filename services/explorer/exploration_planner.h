#pragma once
// Exploration by the distance transform (paper 003 section 4). Each call to PlanFrom:
//  1. builds the configuration space on the coarse exploration grid (configuration_space.h);
//  2. marks every reachable unknown coarse cell as a goal and runs the exploration transform
//     (exploration_transform.h); a robot standing inside the dilation margin (beside a wall after
//     a pirouette) first steps out through cells that hold no obstacle themselves; if no goal can
//     be reached even so, exploration is complete, unless what the planner keeps from refused
//     moves (their obstacles, the goals set aside after them) is all that stands in the way: then
//     it looks all round and tries those goals again (blocked_goal_retries); or unless a way
//     through the margin itself leads to unknown space (squeeze_through_margin: doors narrower
//     than the robot plus both margins), or to unknown space inside the margin (margin_goals: a
//     door's far side), or behind uncertain cells (uncertain_frontier_goals: unseen space
//     bordered by cells seen too seldom to class); or unless a place the robot drove through
//     lately reaches unknown space (the way back, RecordMove); or unless the finer grid of
//     finishing_cell_factor, on which the planner then goes on to the end, still reaches unknown
//     space; or unless return_to_start has not yet looked all round where exploration began (at
//     most three plans back there: a grid that changes on the way, which blocks a move or shows
//     unknown space again, interrupts one); or unless a set-aside goal still unseen can be looked
//     at from afar (set_aside_looks: a plan over free cells to one in plain sight of it, ending
//     facing it);
//  3. descends the transform from the robot's cell to the last free cell before the nearest
//     unknown, and turns that path into piece-wise linear motion (section 2.2): turn on the spot,
//     move straight, with collinear steps merged, ending with a pirouette (12 x 30 degrees;
//     with pirouette_at_goal false, only a plan for unknown space next to the robot pirouettes).
//     With straighten_paths, corners are cut: a waypoint is skipped where the straight move from
//     the one before to the one after stays on cells the descent may use and passes look before
//     you move (the 8-connected descent zigzags across open floor, and each corner is a turn on
//     the spot: a fifth of a second per 10 degrees, and the odometry's least reliable motion).
// A robot closer to an obstacle than its radius (the map moved under it, or a bump) first steps
// straight out of it, and a robot in the margin moves straight to the nearest free cell where it
// can: every move then keeps the full radius (plans from inside the radius began with a move
// past the same obstacle again and again, and each refusal counted against a goal).
// "Look before you move": before each straight move the caller asks IsPathClear with the latest
// grid and replans if it is blocked (ReportBlocked counts that against the goal). PlanFrom puts
// its own moves to the same test and plans around one that would be refused. Goals that stay
// unknown after the robot has looked at them from next door, or that keep being blocked, are set
// aside with a reason, so exploration always ends.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "services/explorer/configuration_space.h"
#include "services/explorer/explorer_config.h"
#include "services/explorer/grid_view.h"
#include "services/explorer/proto/explorer_state.pb.h"

namespace rslam::explorer {

struct MotionCommand {
  enum class Kind { kRotate, kMove, kPirouette, kStop };
  Kind kind = Kind::kStop;
  double angle_rad = 0.0;   // kRotate: turn (counter-clockwise positive); kPirouette: one step
  double distance_m = 0.0;  // kMove: straight ahead (metres)
  int steps = 0;            // kPirouette: number of angle_rad turns, looking after each
};

struct Plan {
  bool complete = false;  // no reachable unknown space remains
  std::vector<MotionCommand> commands;
  std::string reason;
  bool has_target = false;
  Pose2D target;          // where the robot ends (heading of the last move)
  int goal_x = -1;        // coarse cell of the unknown space the plan heads for
  int goal_y = -1;
  bool margin_goal = false;  // that cell is in the margin (ExplorerConfig::margin_goals)
  // Retraces moves the robot drove (the way back, see RecordMove): the caller does not look before
  // these moves, since the grid may have drawn something across them; the base's bumper guards.
  bool way_back = false;
};

struct SetAsideGoal {
  int x = 0;  // coarse cell
  int y = 0;
  std::string reason;
  bool blocked = false;  // set aside after refused moves (tried again, see blocked_goal_retries)
  bool looked = false;   // looked at from afar since (set_aside_looks)
};

class ExplorationPlanner {
 public:
  explicit ExplorationPlanner(ExplorerConfig config);
  ExplorationPlanner(const ExplorationPlanner&) = delete;
  ExplorationPlanner& operator=(const ExplorationPlanner&) = delete;

  // Throws std::invalid_argument for an invalid view, a non-finite pose or a robot off the map.
  Plan PlanFrom(const GridView& occupancy, const Pose2D& robot);

  // Look before you move: true when no occupied cell (or cell off the map) lies within the robot
  // radius of the straight segment from `from` along its heading for distance_m (negative =
  // backwards), except cells the robot is already that close to and moves away from.
  bool IsPathClear(const GridView& occupancy, const Pose2D& from, double distance_m) const;
  // The centre of a cell that blocks that move, if any.
  std::optional<std::pair<double, double>> ObstacleOnPath(const GridView& occupancy, const Pose2D& from,
                                                          double distance_m) const;

  // The robot has finished a pirouette at this pose.
  void RecordPirouette(const Pose2D& where);
  // The robot has driven straight from `from` to `to` (the end of a move, or where the base
  // stopped it): the last way_back_moves such poses are its trail. When no unknown space is
  // reachable from where the robot stands but some is from a pose of its trail, the plan drives
  // back along the trail to the latest such pose instead of calling exploration complete: the
  // grid can draw a wall across the way the robot came in (a map correction moved a wall, or drew
  // it twice), shutting it in (a demo run called exploration complete after 21 s at coverage
  // 0.35, shut in the passage it had just driven into). A way back blocked on the way forgets
  // the trail; at most five are driven in all.
  void RecordMove(const Pose2D& from, const Pose2D& to);
  // A move of this plan was blocked when looked at; after max_blocked_attempts such refusals
  // within 1.5 m of where the plan ends (or without `obstacle`), three times as many farther off,
  // its goal is set aside, and the unseen cells within set_aside_radius_m of it with it.
  // obstacle (world x, y; from ObstacleOnPath): until the next pirouette, plans keep their centre
  // line farther than the robot radius from it. Without that the coarse
  // plan (its cells are classed by the grid cells inside them) can send every goal through the
  // same gap the exact check refuses, and each goal is set aside in turn until exploration calls
  // itself complete.
  void ReportBlocked(const Plan& plan, std::optional<std::pair<double, double>> obstacle = std::nullopt);
  // The base stopped a straight move of this plan (forwards, or backwards when `backwards`) at
  // `at`: something the map does not show is in contact (the camera cannot see the floor
  // boundary closer than its blind range). ReportBlocked with the obstacle one robot radius
  // ahead. Plans keep their cells off such obstacles, and their first step to the centre of the
  // robot's cell as well: that step used to bump into the same wall again and again, which set
  // aside goal after goal until exploration called itself complete with a third of the room
  // unseen (a demo run: 61 goals in 11 s, coverage 0.37).
  void ReportBump(const Plan& plan, const Pose2D& at, bool backwards);

  const std::vector<SetAsideGoal>& set_aside_goals() const { return set_aside_; }
  // The cells this planner keeps (goals set aside, refusals counted) are cells of the grid it last
  // planned on. A grid whose origin has moved (the occupancy service publishes the part of its grid
  // it has seen, which grows) moves them by whole cells to the same places: the sum of those moves.
  std::pair<int, int> cells_shift() const { return cells_shift_; }
  // On the finer grid of finishing_cell_factor (goal and set-aside cells are its cells).
  bool finishing() const { return finishing_; }
  // Occupancy cells per exploration cell a side, on the grid in use.
  int cell_factor() const { return finishing_ ? config_.finishing_cell_factor : config_.coarse_cell_factor; }

  proto::ExplorerState ToProto() const;
  // Replaces this planner's state; validates the whole message first (std::invalid_argument).
  void LoadProto(const proto::ExplorerState& state);
  const ExplorerConfig& config() const { return config_; }

 private:
  void SetAside(int x, int y, std::string reason, bool blocked = false);
  // Moves the kept cells onto the cells of `cs` where its origin differs from the last grid's.
  void FollowGridOrigin(const CoarseGrid& cs);
  // Sets aside (as blocked, with the goal's count of refusals) the unknown and uncertain cells of
  // the last grid planned on within set_aside_radius_m of goal cell (gx, gy).
  void SetAsideAround(int gx, int gy);
  // Goes on to the finer grid: set-aside and blocked goal cells become the cells covering them.
  void StartFinishing();
  // Finer cells per coarse cell a side.
  int FinerPerCoarse() const { return config_.coarse_cell_factor / config_.finishing_cell_factor; }
  // True when the straight segment from `from` along its heading for distance_m passes within the
  // robot radius of an obstacle reported since the last pirouette, closer than its start.
  bool PassesBlockingObstacle(const Pose2D& from, double distance_m) const;
  bool IsSetAside(int x, int y) const;
  // The way back of RecordMove, if the trail has a pose of finite transform cost.
  std::optional<Plan> WayBack(const GridView& occupancy, const CoarseGrid& cs, const std::vector<int32_t>& cost,
                              const Pose2D& robot);
  // Marks as goals the uncertain cells that join unknown space through uncertain cells (not set
  // aside); true if there were any.
  bool AddUncertainFrontierGoals(const CoarseGrid& cs, std::vector<uint8_t>& goal) const;
  // Makes the goals the free traversable cells set_aside_look_min_m..set_aside_look_max_m from a
  // set-aside goal still unknown (or in the margin holding unknown space: margin_goals) and not
  // yet looked at, in plain sight of it (no obstacle cell between the centres), and nothing else;
  // look_target holds that goal's cell index for each (-1 elsewhere). True if there were any.
  bool AddLookGoals(const CoarseGrid& cs, const std::vector<uint8_t>& traversable, std::vector<uint8_t>& goal,
                    std::vector<int32_t>& look_target) const;
  // The straighten_paths shortcut of the header comment: the waypoints from `start` (where the
  // robot stands) that remain.
  std::vector<std::pair<double, double>> Straighten(const GridView& occupancy, const CoarseGrid& cs,
                                                    const std::vector<uint8_t>& traversable,
                                                    std::pair<double, double> start,
                                                    const std::vector<std::pair<double, double>>& waypoints) const;
  // For a robot closer to an obstacle of the grid than its radius: one short straight step that
  // gets it out (the most clearance, straight away from the obstacles or up to 90 degrees off),
  // if one passes look before you move.
  std::optional<Plan> StepOutOfRadius(const GridView& occupancy, const Pose2D& robot) const;
  // For a robot outside the free configuration space: the nearest free cell that can reach a
  // goal (finite cost) within 1 m and a straight move from the robot that passes look before you
  // move, if any.
  std::optional<std::pair<int, int>> DirectEntry(const GridView& occupancy, const CoarseGrid& cs,
                                                 const std::vector<int32_t>& cost,
                                                 const std::vector<uint8_t>& traversable, const Pose2D& robot) const;

  const ExplorerConfig config_;
  std::optional<Pose2D> last_pirouette_;
  std::map<std::pair<int, int>, int> blocked_attempts_;
  std::vector<SetAsideGoal> set_aside_;
  std::vector<std::pair<double, double>> blocking_obstacles_;  // since the last pirouette
  bool finishing_ = false;
  std::vector<Pose2D> trail_;  // RecordMove, oldest first
  int way_backs_ = 0;          // driven so far
  std::optional<Pose2D> start_;      // the robot at the first PlanFrom
  bool returned_to_start_ = false;   // a pirouette within kAtStartM of it (return_to_start)
  int return_attempts_ = 0;          // plans back to it made
  int looks_ = 0;                    // plans made to look at set-aside goals (set_aside_looks)
  CoarseGrid last_grid_;       // the last PlanFrom's (SetAsideAround)
  std::optional<std::pair<double, double>> cells_origin_;  // origin of the grid the kept cells are on
  std::pair<int, int> cells_shift_{0, 0};
};

}  // namespace rslam::explorer
