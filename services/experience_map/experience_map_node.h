#pragma once
// The experience-map service on the bus (RatSLAM experience map, paper 000 eqs. 1-3).
//
// In:  pose_cells/action     (msg::PoseCellAction: one per frame, with the frame's odometry)
// Out: experience_map/pose   (msg::ExperiencePose per applied action: header of its frame)
//      experience_map/map    (msg::ExperienceMap snapshot, state QoS: after changes at most every
//                            map_publish_period_frames actions, and always once the input is
//                            idle, so the latest snapshot carries the last applied action_seq)
//
// Actions are applied strictly in action_seq order: later ones wait in a buffer, duplicates
// (seq <= last applied, e.g. the `log` history replayed after a restart) are ignored, and a
// missing seq that does not come within gap_window_actions / gap_timeout_s is logged, counted as
// rejected and skipped. Per action: integrate its odometry, then apply it; an action whose ids
// do not fit the map is counted as rejected and not applied (its odometry still counts).
//
// State (<state_dir>/experience_map.pb: the map and the last applied action_seq) is saved
// periodically and on shutdown, and reloaded at start unless --fresh; the missed actions then
// come from the pose cells' history. Map files (same format) for users: load_map, merge_map at
// start, save_map on shutdown.

#include <memory>

#include "common/node/service_context.h"
#include "services/experience_map/experience_map_node_config.h"

namespace rslam::experience_map {

class ExperienceMapNode {
 public:
  using Config = ExperienceMapNodeConfig;

  // Throws StateFileError / std::invalid_argument for a corrupt state or map file.
  ExperienceMapNode(ServiceContext& context, const Config& config);
  ~ExperienceMapNode();
  ExperienceMapNode(const ExperienceMapNode&) = delete;
  ExperienceMapNode& operator=(const ExperienceMapNode&) = delete;

  // Periodic state save (every service.state_save_period_s).
  void Tick();

  class Mapper;

 private:
  std::unique_ptr<Mapper> mapper_;
  // Owned here (the context keeps none): destroyed first, which stops its callbacks.
  std::shared_ptr<bus::Subscriber<msg::PoseCellAction>> action_sub_;
};

}  // namespace rslam::experience_map
