#pragma once
// A pose-cell action as it travels on pose_cells/action (one message per frame, carrying the
// frame's odometry), built here for both the service and `rslam run`, so the two never drift.

#include <cstdint>

#include "rslam/msg/all_messages.h"
#include "services/pose_cells/pose_cell_action.h"

namespace rslam::pose_cells {

// The message for a frame's action (header left for the caller). action_seq counts every
// frame's message; the pose-cell position travels as float.
msg::PoseCellAction ToActionMessage(const Action& action, uint64_t action_seq, double vtrans_mps, double vrot_radps,
                                    double dt_s);

}  // namespace rslam::pose_cells
