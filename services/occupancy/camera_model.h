#pragma once
// The floor-looking camera of paper 003 (Taylor, Geva, Boles 2005), section 2.1: pinhole
// intrinsics with OpenCV's distortion model (k1 k2 p1 p2 k3), mounted at a known height above a
// flat floor and tilted down, plus the paper's anti-vignetting: each colour channel is multiplied
// by a gain that grows with the squared distance from the image centre,
//   corrected_c(u, v) = observed_c(u, v) * (1 + k_c * r^2),
// with r the distance from the image centre normalised by the half-diagonal (r = 1 in the
// corners). Per-channel gains also correct a colour tint, as the paper notes.
//
// Order of correction: anti-vignetting acts on the raw sensor image (vignetting is a lens/sensor
// effect centred on the raw image), then undistortion. Both use maps precomputed once.

#include <array>
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <vector>

#include "common/config/config_error.h"

namespace rslam::occupancy {

struct CameraConfig {
  int width = 320;
  int height = 240;
  double fx = 277.13;  // 60 degrees horizontal field of view at 320 px
  double fy = 277.13;
  double cx = 159.5;
  double cy = 119.5;
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;
  double height_m = 0.10;        // optical centre above the floor
  double tilt_rad = 0.5585;      // 32 degrees down from horizontal
  double forward_offset_m = 0.0; // camera ahead of the robot's centre of rotation
  std::vector<double> vignetting_gains = {0.0, 0.0, 0.0};  // k_c for B, G, R

  template <class V>
  void VisitFields(V& v) {
    v("width", width, "image width (px)");
    v("height", height, "image height (px)");
    v("fx", fx, "focal length x (px)");
    v("fy", fy, "focal length y (px)");
    v("cx", cx, "principal point x (px)");
    v("cy", cy, "principal point y (px)");
    v("k1", k1, "radial distortion k1 (OpenCV model)");
    v("k2", k2, "radial distortion k2");
    v("p1", p1, "tangential distortion p1");
    v("p2", p2, "tangential distortion p2");
    v("k3", k3, "radial distortion k3");
    v("height_m", height_m, "camera height above the floor (m)");
    v("tilt_rad", tilt_rad, "camera tilt below horizontal (rad)");
    v("forward_offset_m", forward_offset_m, "camera ahead of the rotation centre (m)");
    v("vignetting_gains", vignetting_gains,
      "anti-vignetting k per channel (B, G, R): gain = 1 + k r^2, r = 1 at the corners");
  }
  void Validate() const;
  // Horizontal field of view of the undistorted pinhole, from its width, cx and fx (degrees).
  double HorizontalFovDeg() const {
    return (std::atan((cx + 0.5) / fx) + std::atan((width - 0.5 - cx) / fx)) * 180.0 / std::numbers::pi;
  }
};

class CameraModel {
 public:
  explicit CameraModel(CameraConfig config);
  CameraModel(const CameraModel&) = delete;
  CameraModel& operator=(const CameraModel&) = delete;

  const CameraConfig& config() const { return config_; }

  // Multiplies each channel by its precomputed gain map. Accepts CV_8UC3 (BGR) or CV_8UC1 (the
  // mean of the three gains is used) of the configured size; throws std::invalid_argument else.
  cv::Mat CorrectVignetting(const cv::Mat& image) const;
  // Removes lens distortion (same intrinsics before and after).
  cv::Mat Undistort(const cv::Mat& image) const;
  // CorrectVignetting then Undistort: the image the floor segmenter expects.
  cv::Mat Correct(const cv::Mat& image) const;

  // Squared normalised radius r^2 of pixel (u, v), as used by the gain model.
  double NormalisedRadiusSquared(double u, double v) const;

 private:
  void CheckImage(const cv::Mat& image) const;

  const CameraConfig config_;
  cv::Mat undistort_map1_, undistort_map2_;
  cv::Mat gain_map_bgr_;   // CV_32FC3
  cv::Mat gain_map_grey_;  // CV_32FC1
};

// Fits the anti-vignetting constants k_c from one image of a flat, uniformly lit, uniform surface:
// observed = T / (1 + k r^2) gives 1/observed = a + b r^2 with k = b / a, solved per channel by
// linear least squares over all pixels (zero pixels are skipped). Returns k for each channel
// (1 or 3 entries). Throws std::invalid_argument for an empty or non-8-bit image.
std::vector<double> FitVignettingGains(const cv::Mat& flat_image);

}  // namespace rslam::occupancy
