#pragma once
// The pose-cell service on the bus (RatSLAM pose cells, paper 000 section II, 001 eqs. 3-4).
//
// In:  odometry/velocity    (msg::Velocity, one per camera frame)
//      templates/view       (msg::ViewTemplate, one per camera frame)
//      experience_map/map   (msg::ExperienceMap, read once at start to resynchronise)
// Out: pose_cells/action    (msg::PoseCellAction, exactly one per processed frame, in frame
//                           order, header = the frame's, action_seq 0, 1, 2, ... per robot,
//                           carrying the frame's odometry; QoS `log`, so a restarted experience
//                           map receives every action it missed)
//
// Odometry and view are joined by header.frame_seq (VelocityViewJoiner) and processed strictly
// in frame order; a frame whose partner never comes (its producer restarted) is processed with
// the side it has: no odometry = no motion, no view = no injection. Malformed inputs (non-finite
// numbers, absurd dt, template ids beyond the next one) are counted as rejected and dropped.
//
// State (<state_dir>/pose_cells.pb: the network and the next action_seq) is saved periodically
// and on shutdown. At start, after loading it, the node waits up to resync_timeout_s for the
// experience map's snapshot: the map may have applied actions beyond the saved state (and hold
// experiences the restored network does not know), or missed some. The node adopts the map's
// experiences and continues action_seq after the map's last applied action, so experience ids
// of the two services can never collide. The frames missed while down moved the robot: they are
// bridged at the recent forward speed, and the first familiar view relocalises the packet.
// Templates learnt while down (their ids fit in the missed frames) are placed when next seen.

#include <memory>

#include "common/node/service_context.h"
#include "services/pose_cells/pose_cells_node_config.h"

namespace rslam::pose_cells {

class PoseCellsNode {
 public:
  using Config = PoseCellsNodeConfig;

  // Throws StateFileError / std::invalid_argument for a corrupt or mismatched state file.
  PoseCellsNode(ServiceContext& context, const Config& config);
  ~PoseCellsNode();
  PoseCellsNode(const PoseCellsNode&) = delete;
  PoseCellsNode& operator=(const PoseCellsNode&) = delete;

  // Periodic state save (every service.state_save_period_s).
  void Tick();

  class Processor;

 private:
  std::unique_ptr<Processor> processor_;
  // Owned here (the context keeps none): destroyed first, which stops their callbacks.
  std::shared_ptr<bus::Subscriber<msg::Velocity>> velocity_sub_;
  std::shared_ptr<bus::Subscriber<msg::ViewTemplate>> view_sub_;
};

}  // namespace rslam::pose_cells
