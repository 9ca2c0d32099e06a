#pragma once
// One camera frame to the odometry service's motion estimate: what the service publishes for a
// frame, without the bus.
//
// The column profiles' velocity (visual_odometry.h, paper 000 eqs. 4-7); with floor odometry on
// (a bgr8 camera of known height over a flat floor of one colour, paper 003), that velocity only
// seeds the registration of the frame's floor boundary (floor_odometry.h), whose motion replaces
// it, and the same boundary gives the frame's wall direction (wall_direction.h). A frame the
// registration cannot measure keeps the profiles' turn and the floor odometry's constant-velocity
// step; a turn on the spot (turns_from_profiles) keeps the profiles' motion, the registration
// still seeing the frame to keep its key frame.
//
// Pure and deterministic: the odometry node and the tests that render frames of the simulator's
// world make exactly the same calls.

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <memory>
#include <optional>
#include <vector>

#include "rslam/msg/all_messages.h"
#include "services/occupancy/obstacle_profile_pipeline.h"
#include "services/odometry/floor_odometry.h"
#include "services/odometry/odometry_node_config.h"
#include "services/odometry/visual_odometry.h"

namespace rslam::odometry {

struct CameraOdometryFrame {
  Velocity velocity;                      // vtrans / vrot over the frame's dt
  std::optional<double> wall_direction;   // floor odometry only (wall_direction.h)
  std::vector<Eigen::Vector2d> boundary;  // floor odometry only: the floor boundary, robot frame
};

class CameraOdometry {
 public:
  // Throws ConfigError on a bad config.
  CameraOdometry(const VisualOdometryConfig& visual, const FloorOdometryNodeConfig& floor);
  CameraOdometry(const CameraOdometry&) = delete;
  CameraOdometry& operator=(const CameraOdometry&) = delete;

  // The motion since the previous frame. image: CV_8UC1 or CV_8UC3 (BGR; required with floor
  // odometry), the same size every frame. dt_s: seconds since the previous frame, > 0; 0 starts
  // anew (the first frame, or after a gap), answered with zero velocity. Throws
  // std::invalid_argument for an image or dt the odometry cannot use; the caller should Reset.
  const CameraOdometryFrame& Update(const cv::Mat& image, double dt_s);

  void Reset();

  // The odometry/velocity message of the last Update (dt_s its dt), as the odometry service
  // publishes it; the header is the caller's.
  msg::Velocity Message(double dt_s) const;

 private:
  // Replaces frame_.velocity by the floor-boundary registration's (see the header comment).
  void FloorMotion(const cv::Mat& image, double dt_s);

  const FloorOdometryNodeConfig floor_config_;
  VisualOdometry visual_;
  std::unique_ptr<occupancy::ObstacleProfilePipeline> boundary_;  // floor odometry only
  std::unique_ptr<FloorOdometry> floor_;
  CameraOdometryFrame frame_;
  bool moved_ = false;  // the previous frame was taken as moving (moving_difference_hold)
};

}  // namespace rslam::odometry
