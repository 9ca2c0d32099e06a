#pragma once
// The simulator process (`rslam-sim`): a simulated robot on the bus, standing in for the robot's
// camera, wheels and a ground-truth tracker.
//
//   publishes  sim/camera            msg::Image (bgr8), one per frame, stamped with simulated time
//              sim/ground_truth      msg::GroundTruthPose (world frame), one per frame
//              robot/wheel_odometry  msg::Velocity (VELOCITY_WHEEL), one per frame
//              robot/motion_feedback msg::MotionFeedback: EXECUTING once, then DONE or BLOCKED
//   subscribes explorer/command      msg::MotionCommand (rotate, move, pirouette, stop)
//              lockstep topics       (default experience_map/pose, occupancy/profile) for pacing
//
// Frames come from a thread of the node: lockstep with the pipeline (rate_hz 0, see
// frame_pacer.h) or at a fixed real-time rate. Every message carries the frame's header
// {robot_id, frame_seq, stamp_ns}; stamps are start_stamp_ns + frame * time_step_s.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/node/frame_pacer.h"
#include "common/node/heartbeat.h"
#include "common/node/service_context.h"
#include "tools/sim/sim_node_config.h"
#include "tools/sim/simulated_robot.h"
#include "tools/sim/world_map.h"

namespace rslam::sim {

// The world file a config names: absolute as is; relative against the working directory first,
// then against the source tree (where the shipped worlds are).
std::string ResolveWorldPath(const std::string& world_yaml);

// The start pose of a config: start_pose, or the world's default start.
Pose2D StartPoseOf(const SimNodeConfig& config, const WorldMap& world);

class SimNode {
 public:
  using Config = SimNodeConfig;

  // Throws ConfigError (bad world file, start pose in a wall) or std::runtime_error.
  SimNode(ServiceContext& context, const Config& config);
  ~SimNode();
  SimNode(const SimNode&) = delete;
  SimNode& operator=(const SimNode&) = delete;

  void Tick();

 private:
  struct PendingCommand {
    uint64_t command_seq = 0;
    MotionCommand command;
  };

  void OnCommand(const msg::MotionCommand& command);
  void OnStageReport(int stage, uint64_t frame_seq);
  void Run();
  // Waits until the pacer lets frame_seq go (lockstep) or its real-time slot comes (rate_hz).
  bool WaitForSlot(uint64_t frame_seq, std::chrono::steady_clock::time_point slot);
  void ApplyPendingCommands(const msg::Header& header);
  void PublishFrame(const SimFrame& frame, const msg::Header& header);
  void PublishFeedback(const msg::Header& header, uint64_t command_seq, msg::MotionState state);
  void SubscribeLockstepTopics();
  // What the services' heartbeats show still unmatched among them (and, in lockstep, lockstep
  // topics no service writes yet); empty = a frame published now reaches every stage.
  std::vector<std::string> UnlinkedServices() const;

  ServiceContext& context_;
  const Config config_;
  const WorldMap world_;
  SimulatedRobot robot_;

  std::shared_ptr<bus::Publisher<msg::Image>> camera_pub_;
  std::shared_ptr<bus::Publisher<msg::GroundTruthPose>> ground_truth_pub_;
  std::shared_ptr<bus::Publisher<msg::Velocity>> wheel_odometry_pub_;
  std::shared_ptr<bus::Publisher<msg::MotionFeedback>> feedback_pub_;
  std::shared_ptr<void> command_sub_;
  std::vector<std::shared_ptr<void>> lockstep_subs_;
  std::vector<std::function<int()>> lockstep_matched_;  // matched publishers per lockstep topic
  ServiceLinkWatch links_;

  std::mutex mutex_;
  std::condition_variable wake_;
  FramePacer pacer_;
  std::deque<PendingCommand> pending_;
  std::optional<uint64_t> running_command_seq_;  // the command the body is executing
  bool stop_ = false;
  Pose2D last_pose_;  // for the periodic log line
  std::chrono::steady_clock::time_point last_frame_time_{};  // lockstep: when the last frame went
  int ticks_ = 0;     // Tick() calls (heartbeat thread only)

  msg::Image image_msg_;  // reused buffer
  std::atomic<uint64_t> frames_published_{0};
  std::thread thread_;
};

}  // namespace rslam::sim
