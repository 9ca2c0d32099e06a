#pragma once
// The odometry service on the bus.
//
// In:  camera/image (msg::Image, mono8 or bgr8 -> grey), or with use_wheel_odometry
//      robot/wheel_odometry (msg::Velocity).
// Out: odometry/velocity (msg::Velocity, header copied from the frame, source VELOCITY_VISUAL;
//      in wheel mode the wheel messages as they are).
//
// Each frame is read by CameraOdometry (camera_odometry.h): the column profiles' velocity, or with
// floor_odometry.enabled (bgr8 images of a camera of known height over a flat floor of one
// colour) the floor-boundary registration's (floor_odometry.h), seeded by the column profiles,
// which stand in for frames it cannot register.
//
// dt is the difference of consecutive frame stamps, never the wall clock. The first frame (and
// the first after a restart of the visual odometry) is answered with zero velocity and dt 0, so
// every camera frame has exactly one velocity and the pose cells can join by frame number. The
// visual odometry restarts that way when the image size changes or when a frame comes more than
// max_frame_gap_s after the previous one (the gap is also counted as rejected), and at frame_seq
// 0 (a restarted camera starts a new run; its stamps may begin below the old run's).
// Rejected (counted, logged once per kind, dropped, the service keeps running): images whose
// sizes disagree with width/height/step/encoding, unknown encodings, more than max_pixels
// pixels, stamps that do not increase, frames the odometry cannot use (crop outside the image);
// wheel messages with non-finite numbers or negative dt.

#include <memory>
#include <vector>

#include "common/node/service_context.h"
#include "services/odometry/odometry_node_config.h"

namespace rslam::odometry {

class OdometryNode {
 public:
  using Config = OdometryNodeConfig;

  OdometryNode(ServiceContext& context, const Config& config);
  ~OdometryNode();
  OdometryNode(const OdometryNode&) = delete;
  OdometryNode& operator=(const OdometryNode&) = delete;

  // Shared with the subscriber's callback thread.
  class Impl;

 private:
  std::shared_ptr<Impl> impl_;
  // The node owns its subscription (the context keeps none): cleared first on destruction.
  std::vector<std::shared_ptr<void>> subscriptions_;
};

}  // namespace rslam::odometry
