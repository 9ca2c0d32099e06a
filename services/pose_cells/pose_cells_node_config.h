#pragma once
// Configuration of the pose-cell service (YAML section `pose_cells`). The network's keys
// (OpenRatSLAM names, see pose_cell_config.h) sit at the top of the section, so a preset file's
// `pose_cells:` section configures the service directly.

#include <cmath>

#include "common/config/config_error.h"
#include "services/pose_cells/pose_cell_config.h"

namespace rslam::pose_cells {

struct PoseCellsNodeConfig {
  PoseCellConfig network;
  // A frame whose odometry or view never comes is processed with the side it has once the other
  // stream is this many frames ahead (its producer died); until then it waits.
  // ...and the frame has waited join_timeout_s.
  int join_window_frames = 20;
  double join_timeout_s = 1.0;
  // At start, wait this long for the experience map's snapshot to resynchronise experience ids
  // and the action sequence (0 = do not wait; a missing map is not an error).
  double resync_timeout_s = 3.0;
  // After a snapshot, keep listening this long for a newer one (the map publishes its catch-up
  // snapshot once its input goes quiet).
  double resync_settle_s = 0.6;
  // After a restart that lost frames, the first familiar view within this many frames moves the
  // activity packet to its place (the robot moved while the service was down); 0 = never.
  int restart_relocalise_frames = 100;
  // Inputs beyond these are refused as malformed.
  double max_dt_s = 60.0;
  double max_vtrans_mps = 500.0;
  double max_vrot_radps = 100.0;

  template <class V>
  void VisitFields(V& v) {
    network.VisitFields(v);
    v("join_window_frames", join_window_frames,
      "frames the live input may run ahead before a frame missing its odometry or view is processed without it");
    v("join_timeout_s", join_timeout_s,
      "seconds a frame missing its odometry or view waits (with the window) before it is processed without it");
    v("resync_timeout_s", resync_timeout_s,
      "seconds to wait at start for the experience map snapshot (resynchronisation); 0 = no wait");
    v("resync_settle_s", resync_settle_s, "seconds to keep listening for a newer snapshot after one arrived");
    v("restart_relocalise_frames", restart_relocalise_frames,
      "after a restart that lost frames, the first familiar view within this many frames relocalises the packet");
    v("max_dt_s", max_dt_s, "largest accepted frame interval (s); larger odometry is refused");
    v("max_vtrans_mps", max_vtrans_mps, "largest accepted |forward speed| (m/s)");
    v("max_vrot_radps", max_vrot_radps, "largest accepted |rotation rate| (rad/s)");
  }

  void Validate() const {
    network.Validate();
    Require(join_window_frames >= 1 && join_window_frames <= 100000, "join_window_frames", "must be in 1..100000");
    Require(std::isfinite(join_timeout_s) && join_timeout_s >= 0 && join_timeout_s <= 600, "join_timeout_s",
            "must be in [0, 600]");
    Require(std::isfinite(resync_timeout_s) && resync_timeout_s >= 0 && resync_timeout_s <= 600, "resync_timeout_s",
            "must be in [0, 600]");
    Require(std::isfinite(resync_settle_s) && resync_settle_s >= 0 && resync_settle_s <= 60, "resync_settle_s",
            "must be in [0, 60]");
    Require(restart_relocalise_frames >= 0, "restart_relocalise_frames", "must be >= 0");
    Require(std::isfinite(max_dt_s) && max_dt_s > 0, "max_dt_s", "must be positive");
    Require(std::isfinite(max_vtrans_mps) && max_vtrans_mps > 0, "max_vtrans_mps", "must be positive");
    Require(std::isfinite(max_vrot_radps) && max_vrot_radps > 0, "max_vrot_radps", "must be positive");
  }
};

}  // namespace rslam::pose_cells
