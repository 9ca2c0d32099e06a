#include "services/occupancy/inverse_perspective_map.h"

#include <cmath>
#include <limits>

namespace rslam::occupancy {

namespace {
// Rays closer than this to the horizon meet the floor too far away to be useful.
constexpr double kMinDownwardComponent = 1e-6;
}  // namespace

InversePerspectiveMap::InversePerspectiveMap(const CameraConfig& camera) : camera_(camera) {
  camera_.Validate();
  table_.create(camera_.height, camera_.width, CV_32FC2);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < camera_.height; ++v) {
    auto* row = table_.ptr<cv::Vec2f>(v);
    for (int u = 0; u < camera_.width; ++u) {
      const auto p = ProjectPixelToFloor(u, v);
      row[u] = p ? cv::Vec2f(static_cast<float>(p->x), static_cast<float>(p->y)) : cv::Vec2f(nan, nan);
    }
  }
}

std::optional<cv::Point2d> InversePerspectiveMap::ProjectPixelToFloor(double u, double v) const {
  const double a = (u - camera_.cx) / camera_.fx;
  const double b = (v - camera_.cy) / camera_.fy;
  const double c = std::cos(camera_.tilt_rad), s = std::sin(camera_.tilt_rad);
  const double down = b * c + s;
  if (down <= kMinDownwardComponent) return std::nullopt;
  const double t = camera_.height_m / down;
  return cv::Point2d(camera_.forward_offset_m + t * (c - b * s), -t * a);
}

std::optional<cv::Point2d> InversePerspectiveMap::ProjectFloorToPixel(double x, double y) const {
  const double c = std::cos(camera_.tilt_rad), s = std::sin(camera_.tilt_rad);
  const double px = x - camera_.forward_offset_m, h = camera_.height_m;
  const double xc = -y;               // along image right
  const double yc = -px * s + h * c;  // along image down
  const double zc = px * c + h * s;   // along the optical axis
  if (zc <= 1e-9) return std::nullopt;
  return cv::Point2d(camera_.cx + camera_.fx * xc / zc, camera_.cy + camera_.fy * yc / zc);
}

std::optional<cv::Point2f> InversePerspectiveMap::FloorPoint(int u, int v) const {
  if (u < 0 || v < 0 || u >= table_.cols || v >= table_.rows) return std::nullopt;
  const cv::Vec2f p = table_.at<cv::Vec2f>(v, u);
  if (std::isnan(p[0])) return std::nullopt;
  return cv::Point2f(p[0], p[1]);
}

}  // namespace rslam::occupancy
