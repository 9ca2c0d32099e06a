#include "services/odometry/visual_odometry.h"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace rslam::odometry {

namespace {

// Sum of a[n] (and of b[n]) over n < count.
void Sums(const float* a, const float* b, int count, float& sum_a, float& sum_b) {
  int n = 0;
#if defined(__SSE2__)
  __m128 va = _mm_setzero_ps(), vb = _mm_setzero_ps();
  for (; n + 4 <= count; n += 4) {
    va = _mm_add_ps(va, _mm_loadu_ps(a + n));
    vb = _mm_add_ps(vb, _mm_loadu_ps(b + n));
  }
  alignas(16) float lanes_a[4], lanes_b[4];
  _mm_store_ps(lanes_a, va);
  _mm_store_ps(lanes_b, vb);
  sum_a = (lanes_a[0] + lanes_a[1]) + (lanes_a[2] + lanes_a[3]);
  sum_b = (lanes_b[0] + lanes_b[1]) + (lanes_b[2] + lanes_b[3]);
#else
  sum_a = sum_b = 0.0f;
#endif
  for (; n < count; ++n) {
    sum_a += a[n];
    sum_b += b[n];
  }
}

// Sum of |a[n] - gain * b[n]| over n < count. SIMD by hand: the compiler may not reorder a
// floating-point reduction on its own.
float AbsoluteDifferenceSum(const float* a, const float* b, float gain, int count) {
  int n = 0;
  float sum = 0.0f;
#if defined(__SSE2__)
  const __m128 sign = _mm_set1_ps(-0.0f);
  const __m128 g = _mm_set1_ps(gain);
  __m128 acc = _mm_setzero_ps();
  for (; n + 4 <= count; n += 4) {
    const __m128 d = _mm_sub_ps(_mm_loadu_ps(a + n), _mm_mul_ps(g, _mm_loadu_ps(b + n)));
    acc = _mm_add_ps(acc, _mm_andnot_ps(sign, d));
  }
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, acc);
  sum = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
#endif
  for (; n < count; ++n) sum += std::abs(a[n] - gain * b[n]);
  return sum;
}

}  // namespace

double ShiftedProfileDifference(std::span<const float> current, std::span<const float> previous, int shift,
                                bool match_gain) {
  const int w = static_cast<int>(current.size());
  if (previous.size() != current.size()) throw std::invalid_argument("profiles differ in length");
  if (std::abs(shift) >= w) throw std::invalid_argument("shift leaves no overlap");
  const int overlap = w - std::abs(shift);
  const float* a = current.data() + std::max(shift, 0);
  const float* b = previous.data() - std::min(shift, 0);
  float gain = 1.0f;
  if (match_gain) {
    float sum_a = 0.0f, sum_b = 0.0f;
    Sums(a, b, overlap, sum_a, sum_b);
    // A black overlap has no exposure to match.
    if (sum_b > 1e-6f && sum_a > 1e-6f) gain = sum_a / sum_b;
  }
  return static_cast<double>(AbsoluteDifferenceSum(a, b, gain, overlap)) / overlap;
}

ProfileMatch BestProfileShift(std::span<const float> current, std::span<const float> previous, int max_shift,
                              int min_overlap, bool match_gain) {
  const int w = static_cast<int>(current.size());
  ProfileMatch best{0, ShiftedProfileDifference(current, previous, 0, match_gain)};
  for (int magnitude = 1; magnitude <= max_shift && w - magnitude > min_overlap; ++magnitude) {
    for (int shift : {magnitude, -magnitude}) {
      const double f = ShiftedProfileDifference(current, previous, shift, match_gain);
      if (f < best.difference) best = {shift, f};
    }
  }
  return best;
}

void ColumnIntensityProfile(const cv::Mat& grey, const cv::Rect& crop, std::vector<float>& profile) {
  profile.assign(crop.width, 0.0f);
  std::vector<uint32_t> sums(crop.width, 0);
  for (int y = crop.y; y < crop.y + crop.height; ++y) {
    const uint8_t* row = grey.ptr<uint8_t>(y) + crop.x;
    for (int x = 0; x < crop.width; ++x) sums[x] += row[x];
  }
  const float scale = 1.0f / (255.0f * static_cast<float>(crop.height));
  for (int x = 0; x < crop.width; ++x) profile[x] = static_cast<float>(sums[x]) * scale;
}

namespace {

cv::Rect ResolveCrop(int x_min, int x_max, int y_min, int y_max, cv::Size image, const char* name) {
  const int x_end = x_max == -1 ? image.width : x_max;
  const int y_end = y_max == -1 ? image.height : y_max;
  if (x_end > image.width || y_end > image.height || x_min >= x_end || y_min >= y_end) {
    throw std::invalid_argument(std::string(name) + " crop x [" + std::to_string(x_min) + ", " +
                                std::to_string(x_end) + ") y [" + std::to_string(y_min) + ", " +
                                std::to_string(y_end) + ") does not fit the " + std::to_string(image.width) + "x" +
                                std::to_string(image.height) + " image");
  }
  return cv::Rect(x_min, y_min, x_end - x_min, y_end - y_min);
}

}  // namespace

VisualOdometry::VisualOdometry(VisualOdometryConfig config) : config_(std::move(config)) { config_.Validate(); }

void VisualOdometry::Reset() {
  has_previous_ = false;
  image_size_ = cv::Size(0, 0);
}

void VisualOdometry::CheckImage(const cv::Mat& grey) const {
  if (grey.empty()) throw std::invalid_argument("VisualOdometry: empty image");
  if (grey.type() != CV_8UC1) {
    throw std::invalid_argument("VisualOdometry: image must be CV_8UC1 (grey), got type " +
                                std::to_string(grey.type()));
  }
  if (has_previous_ && grey.size() != image_size_) {
    throw std::invalid_argument("VisualOdometry: image size changed from " + std::to_string(image_size_.width) +
                                "x" + std::to_string(image_size_.height) + " to " +
                                std::to_string(grey.cols) + "x" + std::to_string(grey.rows));
  }
}

Velocity VisualOdometry::Update(const cv::Mat& grey, double dt_s) {
  CheckImage(grey);
  if (!std::isfinite(dt_s) || dt_s <= 0.0) {
    throw std::invalid_argument("VisualOdometry: dt must be finite and > 0, got " + std::to_string(dt_s));
  }
  if (!has_previous_) {
    const cv::Size size = grey.size();
    const cv::Rect vtrans_crop = ResolveCrop(config_.vtrans_image_x_min, config_.vtrans_image_x_max,
                                             config_.vtrans_image_y_min, config_.vtrans_image_y_max, size, "vtrans");
    const cv::Rect vrot_crop = ResolveCrop(config_.vrot_image_x_min, config_.vrot_image_x_max,
                                           config_.vrot_image_y_min, config_.vrot_image_y_max, size, "vrot");
    for (const cv::Rect& crop : {vtrans_crop, vrot_crop}) {
      if (crop.width <= config_.min_overlap_px) {
        throw std::invalid_argument("VisualOdometry: crop width " + std::to_string(crop.width) +
                                    " must exceed min_overlap_px " + std::to_string(config_.min_overlap_px));
      }
    }
    image_size_ = size;
    vtrans_crop_ = vtrans_crop;
    vrot_crop_ = vrot_crop;
    ColumnIntensityProfile(grey, vtrans_crop_, vtrans_previous_);
    ColumnIntensityProfile(grey, vrot_crop_, vrot_previous_);
    has_previous_ = true;
    return Velocity{};
  }

  ColumnIntensityProfile(grey, vtrans_crop_, vtrans_profile_);
  ColumnIntensityProfile(grey, vrot_crop_, vrot_profile_);
  const ProfileMatch rotation =
      BestProfileShift(vrot_profile_, vrot_previous_, config_.max_shift_px, config_.min_overlap_px,
                       config_.normalise_profile_brightness);
  const ProfileMatch speed =
      BestProfileShift(vtrans_profile_, vtrans_previous_, config_.max_shift_px, config_.min_overlap_px,
                       config_.normalise_profile_brightness);
  std::swap(vtrans_profile_, vtrans_previous_);
  std::swap(vrot_profile_, vrot_previous_);

  const double rad_per_px = config_.camera_fov_deg * std::numbers::pi / 180.0 / image_size_.width;
  Velocity velocity;
  velocity.rotation_shift_px = rotation.shift;
  velocity.vrot = rotation.shift * rad_per_px / dt_s;
  velocity.speed_difference = speed.difference;
  const double moving_difference = std::max(speed.difference - config_.vtrans_noise_floor, 0.0);
  velocity.vtrans =
      std::min(moving_difference * config_.vtrans_scaling / (config_.camera_hz * dt_s), config_.vtrans_max);
  if (config_.turn_in_place_vrot_radps > 0 && std::abs(velocity.vrot) >= config_.turn_in_place_vrot_radps)
    velocity.vtrans = 0.0;
  return velocity;
}

}  // namespace rslam::odometry
