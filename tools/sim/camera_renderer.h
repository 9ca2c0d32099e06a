#pragma once
// Renders what the robot's camera sees in the simulated world: BGR8 images of textured walls
// extruded from the occupancy map, a uniform floor and a uniform ceiling/sky.
//
// Geometry (pinhole mode): the camera sits at height h, forward_offset_m ahead of the robot's
// centre, looking along the robot's heading, tilted down by t (the same model and pixel-centre
// convention, cx = (W - 1) / 2, as services/occupancy's CameraModel). The pixel (u, v) has the ray
//   d = forward * (cos t - y sin t) + left * (-x) + up * (-sin t - y cos t),
//   x = (u + 0.5 - W/2) / f, y = (v + 0.5 - H/2) / f, f = (W/2) / tan(hfov/2),
// i.e. azimuth a = atan2(-x, cos t - y sin t) and rise per metre s = (-sin t - y cos t) / |d_xy|.
// Under tilt an image column does not keep one azimuth, so rays are cast (DDA, exact cell
// boundaries) over a fine fan of azimuths (rays_per_column per column) and each pixel reads the
// ray nearest its own azimuth: the wall at horizontal distance r is hit at height z = h + s r.
// z < 0: floor (the ray meets the floor first), z > wall height: ceiling, else the wall texture
// at (position along the wall, z). Inverse perspective mapping of the first wall row therefore
// recovers the wall distance up to one pixel.
// Panoramic mode: a 360-degree cylinder, one ray per column, rows at uniform elevation angles.
// Per-pixel ray tables are built once; a frame costs one ray cast per azimuth plus a few
// operations per pixel (no trigonometry).

#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

#include "common/math/pose2d.h"
#include "tools/sim/sim_config.h"
#include "tools/sim/wall_texture.h"
#include "tools/sim/world_map.h"

namespace rslam::sim {

class CameraRenderer {
 public:
  // The world must outlive the renderer. Throws ConfigError on a bad config.
  CameraRenderer(const WorldMap& world, const SceneConfig& scene, const CameraConfig& camera);
  CameraRenderer(const CameraRenderer&) = delete;
  CameraRenderer& operator=(const CameraRenderer&) = delete;

  // Renders the view from a ground-truth pose into out (CV_8UC3, reallocated only when needed).
  // frame_index selects the deterministic noise pattern; the same pose and frame_index always
  // give the same image. Throws std::invalid_argument on a non-finite pose.
  // Not thread-safe (uses per-renderer scratch buffers).
  void Render(const Pose2D& pose, uint64_t frame_index, cv::Mat& out);
  cv::Mat Render(const Pose2D& pose, uint64_t frame_index = 0);

  // Azimuth (rad, relative to the heading, left positive) and rise per horizontal metre of the
  // ray through the centre of pixel (u, v). Masked (dead-zone) pixels return false.
  bool PixelRay(int u, int v, double* azimuth, double* rise_per_metre) const;

  double focal_length_px() const { return focal_length_px_; }
  const CameraConfig& camera() const { return camera_; }
  const SceneConfig& scene() const { return scene_; }

 private:
  static constexpr uint16_t kMasked = 0xFFFF;

  void BuildPinholeTables();
  void BuildPanoramicTables();

  const WorldMap& world_;
  const SceneConfig scene_;
  const CameraConfig camera_;
  const WallTexture texture_;
  double focal_length_px_ = 0.0;

  // Per ray: azimuth relative to the heading as a unit vector (forward, left).
  std::vector<double> ray_cos_, ray_sin_;
  std::vector<double> ray_azimuth_;
  // Per pixel (row-major): the ray it reads, and its rise in texels per metre of distance.
  std::vector<uint16_t> pixel_ray_;
  std::vector<float> pixel_rise_texels_;
  std::vector<double> pixel_rise_;  // rise per metre (for PixelRay)
  // Per frame scratch: distance to the wall per ray and the texel column it shows.
  std::vector<float> ray_distance_;
  std::vector<const uint8_t*> ray_column_;
  // Noise values in [-amplitude, amplitude], indexed by (frame offset + byte index) & mask.
  std::vector<int8_t> noise_;
};

}  // namespace rslam::sim
