#pragma once
// The explorer service on the bus (paper 003 section 4: exploration by the distance transform,
// piece-wise linear motion, look before you move).
//
// In:  occupancy/grid         (msg::OccupancyGrid, map frame)
//      experience_map/pose    (msg::ExperiencePose: the robot in the map frame)
//      robot/motion_feedback  (msg::MotionFeedback from the base: EXECUTING, DONE, BLOCKED)
// Out: explorer/command       (msg::MotionCommand, robot-relative: turn by, move by, pirouette,
//                              stop; command_seq increases, also across restarts)
//      explorer/status        (msg::ExplorerStatus on every change, state QoS)
//
// One command is outstanding at a time; the next goes out after its DONE or BLOCKED (or after
// feedback_timeout_s without either: the plan is dropped and made again). Before each straight
// move the path is checked against the latest grid and, if blocked, the goal is reported blocked
// and a new plan made (not on a way back: ExplorationPlanner::RecordMove). A plan ends with a
// pirouette (unless planner.pirouette_at_goal is false); after a plan's last command (and after a
// blocked move) the explorer waits for a grid made after it before planning again. When no
// reachable unknown remains it sends STOP and reports EXPLORATION_COMPLETE. When the service
// stops (SIGTERM) with a command outstanding, it sends STOP and reports EXPLORATION_STOPPED. The
// planner state (goals set aside, blocked counts, obstacles found by refused moves, last
// pirouette, the trail of the last moves, where exploration began) and the command numbering persist in
// <state_dir>/explorer.pb.

#include <memory>
#include <vector>

#include "common/node/service_context.h"
#include "services/explorer/explorer_node_config.h"

namespace rslam::explorer {

class ExplorerNode {
 public:
  using Config = ExplorerNodeConfig;

  // Throws StateFileError / std::invalid_argument for a corrupt state file.
  ExplorerNode(ServiceContext& context, const Config& config);
  ~ExplorerNode();
  ExplorerNode(const ExplorerNode&) = delete;
  ExplorerNode& operator=(const ExplorerNode&) = delete;

  // Feedback and fresh-grid timeouts, periodic state save.
  void Tick();

  // Shared with the subscriber threads (see OccupancyNode: they outlive the node briefly).
  class Controller;

 private:
  std::shared_ptr<Controller> controller_;
  std::vector<std::shared_ptr<void>> subscriptions_;
};

}  // namespace rslam::explorer
