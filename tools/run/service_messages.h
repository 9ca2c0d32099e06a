#pragma once
// What the templates service publishes of a view, applied by `rslam run` too. (The pose-cell
// action travels through services/pose_cells/pose_cell_action_message.h and
// services/experience_map/experience_action_message.h, shared with the services.)

#include <cstdint>

#include "rslam/msg/all_messages.h"

namespace rslam::run {

// The relative angle the templates service publishes (a non-finite angle is sent as 0).
double PublishedRelativeAngle(double relative_angle_rad);

}  // namespace rslam::run
