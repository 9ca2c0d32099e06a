#pragma once
// Configuration of the camera service (YAML section `camera`).
//
// source: `images` (a folder of image files in name order, or a text file listing them),
//         `video` (a video file), `device` (a V4L2 camera), `sim` (the simulator's sim/camera
//         frames, republished). Recorded sources (images, video) are stamped from the source,
//         never from the wall clock, so a replay is deterministic.
// Pacing of recorded sources: rate_hz > 0 publishes in real time at that rate; rate_hz = 0
// publishes as fast as the readers take frames: after each frame the camera waits until every
// matched reader acknowledged it, and (lockstep_topics) until the pipeline's per-frame outputs
// are at most max_frames_in_flight behind, which is what makes it lossless for slow services.
// Devices pace themselves; sim frames are paced by the simulator.

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "common/config/config_error.h"
#include "services/occupancy/camera_model.h"

namespace rslam::camera {

// A rectangle of the source image; width or height 0 = to the image's edge, all 0 = no crop.
struct CropConfig {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;

  template <class V>
  void VisitFields(V& v) {
    v("x", x, "first column");
    v("y", y, "first row");
    v("width", width, "columns (0 = to the right edge)");
    v("height", height, "rows (0 = to the bottom edge)");
  }
  void Validate() const {
    Require(x >= 0, "crop.x", "must be >= 0");
    Require(y >= 0, "crop.y", "must be >= 0");
    Require(width >= 0, "crop.width", "must be >= 0");
    Require(height >= 0, "crop.height", "must be >= 0");
  }
  bool active() const { return x != 0 || y != 0 || width != 0 || height != 0; }
};

struct CameraNodeConfig {
  std::string source = "images";
  std::string path;                     // images: folder or list file; video: file
  std::string device = "/dev/video0";   // device
  int width = 640;                      // device: requested size (0 = the device's default)
  int height = 480;
  double fps = 10.0;                    // images: nominal rate of the stamps; device: requested rate
  int64_t start_stamp_ns = 0;           // images: stamp of the first frame
  double rate_hz = 0.0;                 // recorded sources: 0 = as fast as readers take frames
  int wait_for_readers = 1;             // recorded sources: readers to wait for before frame 0
  double wait_for_readers_timeout_s = 10.0;
  std::vector<std::string> wait_for_services;  // recorded sources: heartbeats to hear before frame 0
  double ack_timeout_s = 10.0;          // rate_hz 0: longest wait for one frame's acknowledgments
  // rate_hz 0: per-frame outputs of the pipeline whose frame_seq paces the camera (common/node/frame_pacer.h).
  std::vector<std::string> lockstep_topics = {"odometry/velocity", "templates/view"};
  int max_frames_in_flight = 4;         // below the sensor preset's depth (8): nothing is overwritten
  double lockstep_timeout_s = 2.0;      // a stage silent this long is not waited for
  double lockstep_startup_timeout_s = 5.0;  // a stage that never reported is waited for this long
  bool loop = false;                    // recorded sources: start again at the end
  CropConfig crop;
  bool grey = false;                    // publish mono8
  bool anti_vignetting = false;         // paper 003's per-channel radial gain (model.vignetting_gains)
  bool undistort = false;               // remove lens distortion (model intrinsics)
  occupancy::CameraConfig model;        // intrinsics, distortion, vignetting of the raw image
  int64_t max_pixels = 16'000'000;      // sim: larger frames are rejected

  template <class V>
  void VisitFields(V& v) {
    v("source", source, "images | video | device | sim");
    v("path", path, "images: folder or list file (one path per line); video: the video file");
    v("device", device, "device: the V4L2 device, e.g. /dev/video0");
    v("width", width, "device: requested width (0 = device default)");
    v("height", height, "device: requested height (0 = device default)");
    v("fps", fps, "images: nominal frame rate of the stamps; device: requested frame rate");
    v("start_stamp_ns", start_stamp_ns, "images: stamp of the first frame (ns)");
    v("rate_hz", rate_hz, "recorded sources: > 0 real-time rate; 0 = as fast as every reader acknowledges");
    v("wait_for_readers", wait_for_readers, "recorded sources: matched readers to wait for before the first frame");
    v("wait_for_services", wait_for_services,
      "recorded sources: services (e.g. [odometry, templates, pose_cells]) whose heartbeats must show their links matched before the first frame");
    v("wait_for_readers_timeout_s", wait_for_readers_timeout_s,
      "how long to wait for them and for the services' heartbeats to show their links matched (then start anyway)");
    v("ack_timeout_s", ack_timeout_s, "rate_hz 0: longest wait for one frame's acknowledgments");
    v("lockstep_topics", lockstep_topics,
      "rate_hz 0: per-frame topics (odometry/velocity, templates/view, pose_cells/action, experience_map/pose, "
      "occupancy/profile) whose frame_seq must catch up before more frames go out; [] = acknowledgments only");
    v("max_frames_in_flight", max_frames_in_flight, "rate_hz 0: frames published ahead of the slowest stage (1..7)");
    v("lockstep_timeout_s", lockstep_timeout_s, "rate_hz 0: a stage silent this long is not waited for");
    v("lockstep_startup_timeout_s", lockstep_startup_timeout_s,
      "rate_hz 0: how long a stage that never reported is waited for");
    v("loop", loop, "recorded sources: start again at the end (seq and stamps keep increasing)");
    v("crop", crop, "crop of the (corrected) image: x, y, width, height (0 = to the edge; all 0 = none)");
    v("grey", grey, "publish mono8 instead of the source's encoding");
    v("anti_vignetting", anti_vignetting, "correct vignetting with model.vignetting_gains (before undistortion)");
    v("undistort", undistort, "remove lens distortion with the model intrinsics");
    v("model", model, "camera model for anti_vignetting / undistort (occupancy camera keys)");
    v("max_pixels", max_pixels, "sim: frames with more pixels are rejected");
  }

  void Validate() const {
    Require(source == "images" || source == "video" || source == "device" || source == "sim", "source",
            "must be images, video, device or sim, got '" + source + "'");
    Require((source != "images" && source != "video") || !path.empty(), "path",
            "needs a folder, list or video file for source " + source);
    Require(source != "device" || !device.empty(), "device", "must name the device, e.g. /dev/video0");
    Require(width >= 0, "width", "must be >= 0");
    Require(height >= 0, "height", "must be >= 0");
    Require(std::isfinite(fps) && fps > 0, "fps", "must be positive");
    Require(std::isfinite(rate_hz) && rate_hz >= 0, "rate_hz", "must be >= 0");
    Require(wait_for_readers >= 0, "wait_for_readers", "must be >= 0");
    Require(std::isfinite(wait_for_readers_timeout_s) && wait_for_readers_timeout_s >= 0,
            "wait_for_readers_timeout_s", "must be >= 0");
    Require(std::isfinite(ack_timeout_s) && ack_timeout_s > 0, "ack_timeout_s", "must be positive");
    for (const auto& topic : lockstep_topics)
      Require(IsLockstepTopic(topic), "lockstep_topics",
              "unknown per-frame topic '" + topic +
                  "' (odometry/velocity, templates/view, pose_cells/action, experience_map/pose, occupancy/profile)");
    Require(max_frames_in_flight >= 1 && max_frames_in_flight <= 7, "max_frames_in_flight",
            "must be in 1..7 (below the camera topic's keep-last depth of 8)");
    Require(std::isfinite(lockstep_timeout_s) && lockstep_timeout_s > 0, "lockstep_timeout_s", "must be positive");
    Require(std::isfinite(lockstep_startup_timeout_s) && lockstep_startup_timeout_s >= 0,
            "lockstep_startup_timeout_s", "must be >= 0");
    crop.Validate();
    if (anti_vignetting || undistort) model.Validate();
    Require(max_pixels >= 1, "max_pixels", "must be >= 1");
  }

  static bool IsLockstepTopic(const std::string& topic) {
    return topic == "odometry/velocity" || topic == "templates/view" || topic == "pose_cells/action" ||
           topic == "experience_map/pose" || topic == "occupancy/profile";
  }
};

}  // namespace rslam::camera
