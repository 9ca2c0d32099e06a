#pragma once
// Inverse perspective mapping (paper 003 section 1, details in Taylor et al. 2004): on a flat
// floor every pixel of the (undistorted) image below the horizon sees exactly one floor point.
// With the camera at height h, tilted down by phi, and the normalised ray (a, b) =
// ((u - cx) / fx, (v - cy) / fy), the ray in the robot frame (x forward, y left, z up) is
//   d = (cos phi - b sin phi, -a, -(b cos phi + sin phi)),
// which meets the floor at t = h / (b cos phi + sin phi) when the denominator is positive:
//   x = forward_offset + t (cos phi - b sin phi),   y = -t a.
// The lookup table holds (x, y) for every pixel (NaN above the horizon), computed once.

#include <opencv2/core.hpp>
#include <optional>

#include "services/occupancy/camera_model.h"

namespace rslam::occupancy {

class InversePerspectiveMap {
 public:
  explicit InversePerspectiveMap(const CameraConfig& camera);
  InversePerspectiveMap(const InversePerspectiveMap&) = delete;
  InversePerspectiveMap& operator=(const InversePerspectiveMap&) = delete;

  // Floor point (robot frame, metres) seen by pixel (u, v), or nothing above the horizon or
  // outside the image. Reads the lookup table.
  std::optional<cv::Point2f> FloorPoint(int u, int v) const;
  // The lookup table itself: CV_32FC2, (x, y) per pixel, NaN where no floor is seen.
  const cv::Mat& table() const { return table_; }

  // The analytic forms, used to build the table and by tests as the oracle.
  std::optional<cv::Point2d> ProjectPixelToFloor(double u, double v) const;
  // Floor point (robot frame) to pixel coordinates (may lie outside the image); nothing when the
  // point is behind the camera.
  std::optional<cv::Point2d> ProjectFloorToPixel(double x, double y) const;

  const CameraConfig& camera() const { return camera_; }

 private:
  const CameraConfig camera_;
  cv::Mat table_;
};

}  // namespace rslam::occupancy
