#pragma once
// What the camera service does to a raw frame before publishing it, in this order:
// anti-vignetting (paper 003 section 2.1, on the raw sensor image where vignetting is centred),
// undistortion, crop, conversion to grey. Each step is optional (CameraNodeConfig).

#include <opencv2/core.hpp>

#include <memory>

#include "services/camera/camera_node_config.h"
#include "services/occupancy/camera_model.h"

namespace rslam::camera {

class FramePreparation {
 public:
  // Throws ConfigError (key model.*) when a correction is on and the model is invalid.
  explicit FramePreparation(const CameraNodeConfig& config);
  FramePreparation(const FramePreparation&) = delete;
  FramePreparation& operator=(const FramePreparation&) = delete;

  // True when Apply returns its input unchanged.
  bool identity() const { return !model_ && !crop_.active() && !grey_; }

  // The prepared frame (CV_8UC1 or CV_8UC3). Throws std::invalid_argument when the frame does
  // not fit: not 8-bit with 1 or 3 channels, a size other than the model's (corrections on), or
  // a crop that does not lie inside it.
  cv::Mat Apply(const cv::Mat& raw) const;

 private:
  const CropConfig crop_;
  const bool grey_;
  const bool anti_vignetting_;
  const bool undistort_;
  const std::unique_ptr<const occupancy::CameraModel> model_;  // only with a correction on
};

}  // namespace rslam::camera
