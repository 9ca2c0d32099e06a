#pragma once
// The whole simulated robot, one tick per camera frame: advance the motion by the configured time
// step, render the camera view from the new ground-truth pose, and measure the wheel odometry of
// the step. What a simulator process publishes per frame (image, ground truth, wheel odometry)
// comes out of Tick(); commands (from the explorer) go into Command().

#include <opencv2/core.hpp>

#include <cstdint>

#include "tools/sim/camera_renderer.h"
#include "common/math/pose2d.h"
#include "tools/sim/proto/sim_state.pb.h"
#include "tools/sim/robot_motion.h"
#include "tools/sim/sim_config.h"
#include "tools/sim/wheel_odometry.h"
#include "tools/sim/world_map.h"

namespace rslam::sim {

struct SimFrame {
  uint64_t index = 0;          // 0, 1, 2, ... (also selects the image noise pattern)
  double time_s = 0.0;         // simulated time the frame was taken
  Pose2D ground_truth;         // robot pose when the frame was taken
  cv::Mat image;               // BGR8, camera.width x camera.height
  WheelOdometryReading wheel_odometry;  // motion since the previous frame
  StepResult motion;           // what the body did since the previous frame
};

class SimulatedRobot {
 public:
  // The world must outlive this. Throws ConfigError on a bad config and std::invalid_argument
  // when the start pose is not free.
  SimulatedRobot(const WorldMap& world, const SimConfig& config, const Pose2D& start);
  SimulatedRobot(const SimulatedRobot&) = delete;
  SimulatedRobot& operator=(const SimulatedRobot&) = delete;

  void Command(const MotionCommand& command) { motion_.Command(command); }
  // Advances one time step and takes a frame. The image is rendered into frame->image, reusing
  // its buffer when the size matches.
  void Tick(SimFrame* frame);
  SimFrame Tick();

  const Pose2D& pose() const { return motion_.pose(); }
  bool busy() const { return motion_.busy(); }
  uint64_t next_frame_index() const { return next_frame_index_; }

  proto::SimulatedRobotState SaveState() const;
  // Throws std::invalid_argument (state unchanged) on a bad or inconsistent state.
  void LoadState(const proto::SimulatedRobotState& state);

 private:
  const SimConfig config_;
  RobotMotion motion_;
  CameraRenderer renderer_;
  WheelOdometry wheel_odometry_;
  uint64_t next_frame_index_ = 0;
};

}  // namespace rslam::sim
