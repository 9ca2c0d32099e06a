#pragma once
// The messages the RatSLAM services pass between them, built and read exactly as the nodes do
// (services/*/..._node.cc), so the runner's stages see the same numbers as the services': the
// pose-cell action travels as msg::PoseCellAction (pose-cell position as float, the frame's
// odometry inside, action_seq counting every frame), and the experience map reads it back.
// The view's relative angle reaches the experience map only once the IDL carries it
// (idl/rslam/pose_cells.idl); until then it arrives as 0, in the services and here alike.
//
// Keep these in step with PoseCellsNode::ProcessFrame and ExperienceMapNode's ToAction.

#include <cstdint>

#include "rslam/msg/all_messages.h"
#include "services/experience_map/experience_action.h"
#include "services/pose_cells/pose_cell_action.h"

namespace rslam::run {

// What the pose-cell service publishes for a frame: its action and the odometry it integrated.
msg::PoseCellAction PoseCellActionMessage(const pose_cells::Action& action, uint64_t action_seq, double vtrans_mps,
                                          double vrot_radps, double dt_s);

// What the experience-map service applies for that message.
experience_map::ExperienceAction ExperienceActionFromMessage(const msg::PoseCellAction& message);

// The relative angle the templates service publishes (a non-finite angle is sent as 0).
double PublishedRelativeAngle(double relative_angle_rad);

}  // namespace rslam::run
