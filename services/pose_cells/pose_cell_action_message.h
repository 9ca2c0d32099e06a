#pragma once
// A pose-cell action as it travels on pose_cells/action (one message per frame, carrying the
// frame's odometry), built here for the service, `rslam run` and `rslam eval map`, so they never
// drift.

#include <cstdint>
#include <optional>

#include "rslam/msg/all_messages.h"
#include "services/pose_cells/pose_cell_action.h"
#include "services/pose_cells/pose_cell_network.h"

namespace rslam::pose_cells {

// The message for a frame's action (header left for the caller). action_seq counts every
// frame's message; the pose-cell position travels as float.
msg::PoseCellAction ToActionMessage(const Action& action, uint64_t action_seq, double vtrans_mps, double vrot_radps,
                                    double dt_s);

// The odometry a frame integrates: its velocity's, or, when that never came, no motion over the
// time since the last frame processed (none before the first; at most max_dt_s), so the map's links
// still get their travel time.
struct FrameOdometry {
  double vtrans_mps = 0.0, vrot_radps = 0.0, dt_s = 0.0;
};
FrameOdometry OdometryOf(const msg::Velocity* velocity, int64_t stamp_ns, std::optional<int64_t> last_stamp_ns,
                         double max_dt_s);

// One joined frame through the network as the service processes it: the velocity's floor boundary
// goes in when the network uses boundaries, and the action message carries the frame's header,
// the odometry it integrated (OdometryOf) and the velocity's wall direction. velocity or view may
// be null (that side of the frame never came). scratch is reused between calls. Throws std::invalid_argument as
// PoseCellNetwork::ProcessFrame (network unchanged).
struct FrameStep {
  Action action;
  msg::PoseCellAction message;
};
FrameStep StepFrame(PoseCellNetwork& network, const msg::Header& header, const msg::Velocity* velocity,
                    const FrameOdometry& odometry, const msg::ViewTemplate* view, uint64_t action_seq,
                    FloorBoundary& scratch);

}  // namespace rslam::pose_cells
