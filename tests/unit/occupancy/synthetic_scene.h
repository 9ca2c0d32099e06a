#pragma once
// Test helper: renders what the floor camera sees in a world of a flat floor of one colour and
// vertical walls (textured, or plain-coloured obstacles), by casting the ray of every pixel. It
// also returns the true floor mask, so segmentation and profiles can be checked exactly.

#include <cmath>
#include <optional>
#include <opencv2/core.hpp>
#include <vector>

#include "services/occupancy/inverse_perspective_map.h"
#include "common/math/pose2d.h"

namespace rslam::occupancy::testing {

struct Wall {
  cv::Point2d a, b;   // footprint on the floor, world frame (m)
  double height_m = 0.3;
  bool textured = true;
  cv::Vec3b colour{40, 40, 200};
};

// The flat top of a box obstacle (world frame, axis-aligned).
struct BoxTop {
  double x0, y0, x1, y1, height_m;
  cv::Vec3b colour;
};

struct RenderedView {
  cv::Mat image;       // CV_8UC3
  cv::Mat true_floor;  // CV_8U, 255 where the pixel sees the floor
};

inline const cv::Vec3b kFloorColour{70, 150, 90};

// Distance along the 2-D direction (dx, dy) from p to segment w, if they meet.
inline std::optional<double> RayHitsSegment(cv::Point2d p, double dx, double dy, const Wall& w) {
  const double ex = w.b.x - w.a.x, ey = w.b.y - w.a.y;
  const double det = dx * (-ey) - dy * (-ex);
  if (std::abs(det) < 1e-12) return std::nullopt;
  const double qx = w.a.x - p.x, qy = w.a.y - p.y;
  const double t = (qx * (-ey) - qy * (-ex)) / det;
  const double s = (dx * qy - dy * qx) / det;
  if (t <= 0 || s < 0 || s > 1) return std::nullopt;
  return t;
}

// Analytic range along a world bearing from p to the first wall (for ROP oracles).
inline double TrueRange(cv::Point2d p, double bearing, const std::vector<Wall>& walls) {
  double best = 1e9;
  for (const Wall& w : walls)
    if (auto t = RayHitsSegment(p, std::cos(bearing), std::sin(bearing), w)) best = std::min(best, *t);
  return best;
}

inline RenderedView Render(const CameraConfig& cam, const Pose2D& robot, const std::vector<Wall>& walls,
                           double noise_sigma = 3.0, uint64_t seed = 1, const std::vector<BoxTop>& tops = {}) {
  RenderedView out{cv::Mat(cam.height, cam.width, CV_8UC3), cv::Mat::zeros(cam.height, cam.width, CV_8U)};
  const double c = std::cos(cam.tilt_rad), s = std::sin(cam.tilt_rad);
  const double ct = std::cos(robot.theta), st = std::sin(robot.theta);
  const cv::Point2d cam_xy(robot.x + cam.forward_offset_m * ct, robot.y + cam.forward_offset_m * st);
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const double a = (u - cam.cx) / cam.fx, b = (v - cam.cy) / cam.fy;
      // Ray in the robot frame, then rotated into the world.
      const double rx = c - b * s, ry = -a, rz = -(b * c + s);
      const double wx = ct * rx - st * ry, wy = st * rx + ct * ry;
      double best_t = rz < 0 ? cam.height_m / -rz : 1e9;  // the floor
      cv::Vec3b colour = rz < 0 ? kFloorColour : cv::Vec3b(30, 30, 30);
      bool floor = rz < 0;
      for (const Wall& w : walls) {
        const auto t = RayHitsSegment(cam_xy, wx, wy, w);
        if (!t || *t >= best_t) continue;
        const double z = cam.height_m + *t * rz;
        if (z < 0 || z > w.height_m) continue;
        best_t = *t;
        floor = false;
        if (w.textured) {
          const double along = std::hypot(cam_xy.x + *t * wx - w.a.x, cam_xy.y + *t * wy - w.a.y);
          const bool dark = (static_cast<int>(std::floor(along / 0.02)) + static_cast<int>(std::floor(z / 0.02))) % 2;
          colour = dark ? cv::Vec3b(60, 50, 140) : cv::Vec3b(210, 205, 190);
        } else {
          colour = w.colour;
        }
      }
      for (const BoxTop& top : tops) {
        if (rz >= 0) break;
        const double t = (cam.height_m - top.height_m) / -rz;
        const double px = cam_xy.x + t * wx, py = cam_xy.y + t * wy;
        if (t > 0 && t < best_t && px >= top.x0 && px <= top.x1 && py >= top.y0 && py <= top.y1) {
          best_t = t;
          floor = false;
          colour = top.colour;
        }
      }
      out.image.at<cv::Vec3b>(v, u) = colour;
      out.true_floor.at<uchar>(v, u) = floor ? 255 : 0;
    }
  }
  if (noise_sigma > 0) {
    cv::Mat noise(out.image.size(), CV_16SC3);
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0, noise_sigma);
    cv::Mat image16;
    out.image.convertTo(image16, CV_16SC3);
    image16 += noise;
    image16.convertTo(out.image, CV_8UC3);
  }
  return out;
}

// Four walls of a box obstacle (plain colour) with corners (x0, y0)-(x1, y1).
inline std::vector<Wall> Box(double x0, double y0, double x1, double y1, double height, cv::Vec3b colour) {
  const cv::Point2d p[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  std::vector<Wall> walls;
  for (int i = 0; i < 4; ++i) walls.push_back(Wall{p[i], p[(i + 1) % 4], height, false, colour});
  return walls;
}

inline std::vector<Wall> SquareRoom(double half_side) {
  const double h = half_side;
  return {Wall{{-h, -h}, {h, -h}}, Wall{{h, -h}, {h, h}}, Wall{{h, h}, {-h, h}}, Wall{{-h, h}, {-h, -h}}};
}

inline double IoU(const cv::Mat& a, const cv::Mat& b) {
  const int inter = cv::countNonZero(a & b), uni = cv::countNonZero(a | b);
  return uni == 0 ? 1.0 : static_cast<double>(inter) / uni;
}

}  // namespace rslam::occupancy::testing
