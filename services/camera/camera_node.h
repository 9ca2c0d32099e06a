#pragma once
// The camera service on the bus: frames from a source, numbered and stamped, on camera/image.
//
// In:  a V4L2 device, a video file or an image folder/list (services/camera/frame_source.h), or
//      sim/camera (msg::Image from the simulator; its frame_seq and stamp are kept).
// Out: camera/image (msg::Image, header {robot_id, frame_seq, stamp_ns}), anti-vignetted,
//      undistorted, cropped and/or grey as configured (frame_preparation.h).
//
// Recorded sources are stamped by the source (deterministic). rate_hz > 0 paces them in real
// time; rate_hz = 0 publishes the next frame once every matched reader acknowledged the last one.
// Before frame 0 the camera waits for wait_for_readers readers and for the heartbeats of the
// wait_for_services to show their links, its own camera/image included, matched at both ends (up
// to its timeout; at a set rate a writer-side match alone loses the first frames). At the end
// of a finite source it logs the end and stops the process cleanly (exit 0), unless `loop`:
// then the source starts again with frame numbers and stamps continuing upwards.
// Start-up failures (absent device, unreadable first frame) throw: the process exits 1; a bad
// crop or camera model is a ConfigError: exit 2. A live device that stops delivering ends the
// process with exit 1 (a supervisor restarts it; the camera keeps no state). An unreadable image
// in the middle of a folder is counted as rejected and skipped (its frame number stays unused).

#include <memory>
#include <vector>

#include "common/node/service_context.h"
#include "services/camera/camera_node_config.h"

namespace rslam::camera {

class CameraNode {
 public:
  using Config = CameraNodeConfig;

  CameraNode(ServiceContext& context, const Config& config);
  ~CameraNode();
  CameraNode(const CameraNode&) = delete;
  CameraNode& operator=(const CameraNode&) = delete;

  // Shared with the frame thread and the sim subscriber's callback thread.
  class Impl;

 private:
  std::shared_ptr<Impl> impl_;
  // The node owns its subscriptions (the context keeps none): cleared first on destruction.
  std::vector<std::shared_ptr<void>> subscriptions_;
};

}  // namespace rslam::camera
