#include "tools/sim/camera_renderer.h"

#include "tools/sim/deterministic_random.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rslam::sim {

namespace {

constexpr size_t kNoiseSize = size_t{1} << 20;

template <class T>
const T& Validated(const T& cfg) {
  cfg.Validate();
  return cfg;
}

}  // namespace

CameraRenderer::CameraRenderer(const WorldMap& world, const SceneConfig& scene, const CameraConfig& camera)
    : world_(world), scene_(Validated(scene)), camera_(Validated(camera)), texture_(scene_) {
  if (camera_.panoramic) {
    BuildPanoramicTables();
  } else {
    BuildPinholeTables();
  }
  ray_distance_.resize(ray_cos_.size());
  ray_column_.resize(ray_cos_.size());
  if (camera_.noise_amplitude > 0) {
    noise_.resize(kNoiseSize);
    uint64_t state = SplitMix64(camera_.noise_seed);
    const int span = 2 * camera_.noise_amplitude + 1;
    for (auto& n : noise_) {
      state = SplitMix64(state);
      n = static_cast<int8_t>(static_cast<int>(state % span) - camera_.noise_amplitude);
    }
  }
}

void CameraRenderer::BuildPinholeTables() {
  const int w = camera_.width, h = camera_.height;
  const double t = camera_.tilt_rad;
  focal_length_px_ = (w / 2.0) / std::tan(camera_.horizontal_fov_rad / 2.0);
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<double> azimuth(n);
  pixel_rise_.resize(n);
  double min_azimuth = 1e9, max_azimuth = -1e9;
  for (int v = 0; v < h; ++v) {
    const double y = (v + 0.5 - h / 2.0) / focal_length_px_;
    for (int u = 0; u < w; ++u) {
      const double x = (u + 0.5 - w / 2.0) / focal_length_px_;
      const double forward = std::cos(t) - y * std::sin(t);
      const double left = -x;
      const double up = -std::sin(t) - y * std::cos(t);
      const size_t i = static_cast<size_t>(v) * w + u;
      azimuth[i] = std::atan2(left, forward);
      pixel_rise_[i] = up / std::hypot(forward, left);
      min_azimuth = std::min(min_azimuth, azimuth[i]);
      max_azimuth = std::max(max_azimuth, azimuth[i]);
    }
  }
  const int rays = std::clamp(static_cast<int>(std::ceil(w * camera_.rays_per_column)), 2, kMasked - 1);
  const double step = (max_azimuth - min_azimuth) / (rays - 1);
  ray_azimuth_.resize(rays);
  for (int k = 0; k < rays; ++k) ray_azimuth_[k] = min_azimuth + k * step;
  pixel_ray_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    pixel_ray_[i] = static_cast<uint16_t>(
        std::clamp(static_cast<int>(std::lround((azimuth[i] - min_azimuth) / step)), 0, rays - 1));
  }
  ray_cos_.resize(rays);
  ray_sin_.resize(rays);
  for (int k = 0; k < rays; ++k) {
    ray_cos_[k] = std::cos(ray_azimuth_[k]);
    ray_sin_[k] = std::sin(ray_azimuth_[k]);
  }
  pixel_rise_texels_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    pixel_rise_texels_[i] = static_cast<float>(pixel_rise_[i] * texture_.texels_per_metre_up());
  }
}

void CameraRenderer::BuildPanoramicTables() {
  const int w = camera_.width, h = camera_.height;
  if (w >= kMasked) throw std::invalid_argument("CameraRenderer: panorama too wide");
  focal_length_px_ = w / (2.0 * M_PI);  // pixels per radian of azimuth
  ray_azimuth_.resize(w);
  ray_cos_.resize(w);
  ray_sin_.resize(w);
  std::vector<bool> masked(w, false);
  for (int u = 0; u < w; ++u) {
    // Centre column straight ahead; azimuth decreases to the right.
    const double a = M_PI - 2.0 * M_PI * (u + 0.5) / w;
    ray_azimuth_[u] = a;
    ray_cos_[u] = std::cos(a);
    ray_sin_[u] = std::sin(a);
    masked[u] = camera_.dead_zone_width_rad > 0 &&
                std::abs(WrapAngle(a - camera_.dead_zone_center_rad)) < camera_.dead_zone_width_rad / 2.0;
  }
  const size_t n = static_cast<size_t>(w) * h;
  pixel_ray_.resize(n);
  pixel_rise_.resize(n);
  pixel_rise_texels_.resize(n);
  for (int v = 0; v < h; ++v) {
    const double elevation = -camera_.tilt_rad + camera_.vertical_fov_rad * (0.5 - (v + 0.5) / h);
    const double rise = std::tan(elevation);
    for (int u = 0; u < w; ++u) {
      const size_t i = static_cast<size_t>(v) * w + u;
      pixel_ray_[i] = masked[u] ? kMasked : static_cast<uint16_t>(u);
      pixel_rise_[i] = rise;
      pixel_rise_texels_[i] = static_cast<float>(rise * texture_.texels_per_metre_up());
    }
  }
}

bool CameraRenderer::PixelRay(int u, int v, double* azimuth, double* rise_per_metre) const {
  if (u < 0 || v < 0 || u >= camera_.width || v >= camera_.height) {
    throw std::invalid_argument("PixelRay: pixel outside the image");
  }
  const size_t i = static_cast<size_t>(v) * camera_.width + u;
  if (pixel_ray_[i] == kMasked) return false;
  *azimuth = ray_azimuth_[pixel_ray_[i]];
  *rise_per_metre = pixel_rise_[i];
  return true;
}

cv::Mat CameraRenderer::Render(const Pose2D& pose, uint64_t frame_index) {
  cv::Mat out;
  Render(pose, frame_index, out);
  return out;
}

void CameraRenderer::Render(const Pose2D& pose, uint64_t frame_index, cv::Mat& out) {
  if (!IsFinite(pose)) throw std::invalid_argument("CameraRenderer::Render: non-finite pose");
  const int w = camera_.width, h = camera_.height;
  out.create(h, w, CV_8UC3);

  // One ray cast per azimuth.
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const Eigen::Vector2d from(pose.x + camera_.forward_offset_m * c, pose.y + camera_.forward_offset_m * s);
  const size_t rays = ray_cos_.size();
  for (size_t k = 0; k < rays; ++k) {
    const Eigen::Vector2d dir(c * ray_cos_[k] - s * ray_sin_[k], s * ray_cos_[k] + c * ray_sin_[k]);
    const RayHit hit = world_.CastRay(from, dir);
    ray_distance_[k] = static_cast<float>(hit.distance);
    ray_column_[k] = texture_.Column(hit);
  }

  // Per pixel: height of the wall hit in texels decides floor / wall / ceiling.
  const float eye_texels = static_cast<float>(camera_.height_m * texture_.texels_per_metre_up());
  const float top_texels = static_cast<float>(WallTexture::kTexelsUp);
  const uint8_t floor_bgr[3] = {static_cast<uint8_t>(scene_.floor_bgr[0]), static_cast<uint8_t>(scene_.floor_bgr[1]),
                                static_cast<uint8_t>(scene_.floor_bgr[2])};
  const uint8_t ceiling_bgr[3] = {static_cast<uint8_t>(scene_.ceiling_bgr[0]),
                                  static_cast<uint8_t>(scene_.ceiling_bgr[1]),
                                  static_cast<uint8_t>(scene_.ceiling_bgr[2])};
  const bool noisy = !noise_.empty();
  const size_t noise_mask = kNoiseSize - 1;
  const size_t noise_offset = noisy ? SplitMix64(frame_index ^ (uint64_t{camera_.noise_seed} << 32)) & noise_mask : 0;
  const bool noise_on_floor = camera_.noise_on_floor;
  const uint16_t* pixel_ray = pixel_ray_.data();
  const float* rise = pixel_rise_texels_.data();
  const float* distance = ray_distance_.data();
  const uint8_t* const* column = ray_column_.data();
  for (int v = 0; v < h; ++v) {
    uint8_t* row = out.ptr<uint8_t>(v);
    const size_t base = static_cast<size_t>(v) * w;
    for (int u = 0; u < w; ++u) {
      const size_t i = base + u;
      const uint16_t k = pixel_ray[i];
      uint8_t* px = row + 3 * u;
      bool is_floor = false;
      if (k == kMasked) {
        px[0] = px[1] = px[2] = 0;
        continue;
      }
      const float z = eye_texels + rise[i] * distance[k];
      const uint8_t* colour;
      if (z < 0.0f) {
        colour = floor_bgr;
        is_floor = true;
      } else if (z >= top_texels) {
        colour = ceiling_bgr;
      } else {
        colour = column[k] + 3 * static_cast<int>(z);
      }
      if (noisy && (!is_floor || noise_on_floor)) {
        const size_t n = (noise_offset + 3 * i) & noise_mask;
        for (int ch = 0; ch < 3; ++ch) {
          px[ch] = static_cast<uint8_t>(std::clamp(colour[ch] + noise_[(n + ch) & noise_mask], 0, 255));
        }
      } else {
        px[0] = colour[0];
        px[1] = colour[1];
        px[2] = colour[2];
      }
    }
  }
}

}  // namespace rslam::sim
