#pragma once
// Configuration of the simulator process (YAML section `sim:`): the simulator library's SimConfig
// flattened into the section (world_yaml, scene, camera, motion, wheel_odometry) plus the keys of
// the process itself (start pose, stamps, pacing, frame limit).

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "common/config/config_error.h"
#include "tools/sim/sim_config.h"

namespace rslam::sim {

struct SimNodeConfig {
  SimConfig sim;
  // [x_m, y_m, theta_rad] in the world frame; empty = the world's default start.
  std::vector<double> start_pose;
  // Stamp of frame 0 (ns since the Unix epoch); frame N is stamped start + N * time_step_s, so a
  // run is the same whatever the wall clock says. 2026-01-01T00:00:00Z.
  int64_t start_stamp_ns = 1767225600000000000;
  // 0 = lockstep: as fast as the pipeline goes; > 0 = a fixed real-time frame rate.
  double rate_hz = 0.0;
  // Lockstep: frame N is published once every live stage has reported frame >= N - this.
  int max_frames_in_flight = 2;
  // Lockstep: per-frame topics whose frame_seq marks a stage as done with a frame (one of
  // camera/image, odometry/velocity, templates/view, pose_cells/action, experience_map/pose,
  // occupancy/profile).
  std::vector<std::string> lockstep_topics = {"experience_map/pose", "occupancy/profile"};
  // A stage that has reported before but stays silent this long is not waited for any more (until
  // it reports again), so a crashed stage stalls the sim once, not forever; meanwhile frames go
  // out in real time (one per time step).
  double lockstep_timeout_s = 2.0;
  // A stage that has never reported is waited for this long after the first frame (services
  // start, join the bus and discover each other in this time).
  double startup_timeout_s = 15.0;
  // Before the first frame, wait up to this long for a reader of sim/camera (the camera service),
  // a publisher on every lockstep topic, and heartbeats showing the services in between matched
  // to each other. 0 = start at once.
  double wait_for_pipeline_s = 20.0;
  std::vector<std::string> wait_for_services;  // heartbeats to hear first (`rslam demo`: all seven)
  // Frames to publish (0 = unlimited); then the process stops (exit 0).
  int64_t max_frames = 0;

  template <class V>
  void VisitFields(V& v) {
    sim.VisitFields(v);
    v("start_pose", start_pose, "[x_m, y_m, theta_rad] start in the world; empty = the world's default start");
    v("start_stamp_ns", start_stamp_ns, "stamp of frame 0 (ns since the epoch); frame N adds N time steps");
    v("rate_hz", rate_hz, "0 = lockstep with the pipeline (as fast as it goes); > 0 = fixed real-time rate");
    v("max_frames_in_flight", max_frames_in_flight, "lockstep: frames published ahead of the slowest stage");
    v("lockstep_topics", lockstep_topics, "lockstep: per-frame topics whose frame_seq marks a stage done");
    v("lockstep_timeout_s", lockstep_timeout_s, "lockstep: a stage silent this long is not waited for");
    v("startup_timeout_s", startup_timeout_s, "lockstep: how long a stage that never reported is waited for");
    v("wait_for_pipeline_s", wait_for_pipeline_s,
      "before frame 0, wait up to this long for a sim/camera reader, the lockstep topics' publishers and "
      "the services' heartbeats showing them matched to each other");
    v("wait_for_services", wait_for_services,
      "services whose heartbeats must be heard (and show their links matched) before frame 0");
    v("max_frames", max_frames, "frames to publish, then stop (0 = unlimited)");
  }

  void Validate() const {
    sim.Validate();
    Require(start_pose.empty() || start_pose.size() == 3, "start_pose", "must be empty or [x_m, y_m, theta_rad]");
    for (double value : start_pose) Require(std::isfinite(value), "start_pose", "must be finite");
    Require(start_stamp_ns >= 0, "start_stamp_ns", "must be >= 0");
    Require(std::isfinite(rate_hz) && rate_hz >= 0 && rate_hz <= 10000, "rate_hz", "must be in [0, 10000]");
    Require(max_frames_in_flight >= 1 && max_frames_in_flight <= 1000, "max_frames_in_flight",
            "must be in [1, 1000]");
    for (const auto& topic : lockstep_topics)
      Require(IsLockstepTopic(topic), "lockstep_topics",
              "unknown per-frame topic '" + topic +
                  "' (camera/image, odometry/velocity, templates/view, pose_cells/action, experience_map/pose, "
                  "occupancy/profile)");
    Require(std::isfinite(lockstep_timeout_s) && lockstep_timeout_s > 0, "lockstep_timeout_s", "must be positive");
    Require(std::isfinite(startup_timeout_s) && startup_timeout_s >= 0, "startup_timeout_s", "must be >= 0");
    Require(std::isfinite(wait_for_pipeline_s) && wait_for_pipeline_s >= 0, "wait_for_pipeline_s", "must be >= 0");
    Require(max_frames >= 0, "max_frames", "must be >= 0");
  }

  static bool IsLockstepTopic(const std::string& topic) {
    return topic == "camera/image" || topic == "odometry/velocity" || topic == "templates/view" ||
           topic == "pose_cells/action" || topic == "experience_map/pose" || topic == "occupancy/profile";
  }
};

}  // namespace rslam::sim
