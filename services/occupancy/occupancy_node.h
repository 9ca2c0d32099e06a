#pragma once
// The occupancy service on the bus (paper 003 mapping, anchored to the RatSLAM experience map).
//
// In:  camera/image          (msg::Image, "bgr8" or "mono8", the configured camera size)
//      experience_map/pose   (msg::ExperiencePose, one per frame: robot and current experience)
//      experience_map/map    (msg::ExperienceMap snapshot: corrected experience poses)
// Out: occupancy/profile     (msg::ObstacleProfile per joined frame, the frame's header)
//      occupancy/grid        (msg::OccupancyGrid every grid_publish_every_n_frames frames and
//                             after every rebuild; map_version = the experience map version
//                             whose poses the grid stands on: the newest snapshot applied)
//
// Image and pose are joined by header.frame_seq. Each joined frame gives one Radial Obstacle
// Profile, anchored to the current experience and inserted into the grid. When a map snapshot
// moves experiences the profiles were anchored to, the grid is rebuilt from the corrected poses.
// State (the anchored profiles) is saved to <state_dir>/occupancy.pb periodically and on
// shutdown, and reloaded at start unless --fresh; on shutdown the grid is also exported as
// grid.pgm + grid.yaml (ROS map_server) and occupancy.png into the state dir.

#include <memory>
#include <vector>

#include "common/node/service_context.h"
#include "services/occupancy/occupancy_node_config.h"

namespace rslam::occupancy {

class OccupancyNode {
 public:
  using Config = OccupancyNodeConfig;

  // Throws StateFileError / std::invalid_argument for a corrupt state file.
  OccupancyNode(ServiceContext& context, const Config& config);
  ~OccupancyNode();
  OccupancyNode(const OccupancyNode&) = delete;
  OccupancyNode& operator=(const OccupancyNode&) = delete;

  // Periodic state save (every service.state_save_period_s).
  void Tick();

  // Shared with the subscriber threads, which the runtime keeps alive a little longer than the
  // node: they hold the mapper and find it stopped.
  class Mapper;

 private:
  std::shared_ptr<Mapper> mapper_;
  std::vector<std::shared_ptr<void>> subscriptions_;
};

}  // namespace rslam::occupancy
