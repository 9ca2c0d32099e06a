#include "services/odometry/visual_odometry.h"

#include "common/image/crop.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace rslam::odometry {

namespace {

// The shift two halves share (rotation_from_halves, visual_odometry_config.h): none when they
// move apart or one stands still, else the smaller.
double SharedShift(double left, double right) {
  if ((left > 0) != (right > 0) || left == 0 || right == 0) return 0.0;
  return std::abs(left) < std::abs(right) ? left : right;
}

// The turn the halves give: the shift they share, except in a steady turn on the spot (the last
// two frames turns on the spot, `previous` and `before` within `tolerance` px of each other), where
// halves more than `tolerance` apart give the one within `tolerance` of `previous`
// (turn_continuity_px; 0 = always the shared shift), unless both move as a forward drive moves
// them by fewer than `forward_px` px (turn_continuity_forward_px). Halves sharing no shift right
// after a turn on the spot give the one within `follow` px of `previous` (turn_follow_px; 0 = off)
// if it moves as no forward drive moves it.
double HalvesShift(double left, double right, std::optional<double> previous, std::optional<double> before,
                   double tolerance, double follow, double forward_px) {
  const double l = previous ? std::abs(left - *previous) : 0.0, r = previous ? std::abs(right - *previous) : 0.0;
  const bool steady_turn = tolerance > 0 && previous && before && std::abs(*previous - *before) <= tolerance;
  if (steady_turn && std::abs(left - right) > tolerance && std::min(l, r) <= tolerance) {
    const bool drive = left < 0 && right > 0 && std::max(-left, right) < forward_px;
    if (!drive) return l <= r ? left : right;
  }
  const double shared = SharedShift(left, right);
  // The turn followed must not itself have jumped from the frame before (a turn's end misread).
  const bool followable = previous && (!before || std::abs(*previous - *before) <= follow);
  if (shared == 0 && follow > 0 && followable) {
    // Driving forward moves the left half's view left (< 0) and the right half's right (> 0), so
    // only a left half moving right or a right half moving left can be the turn going on.
    const bool left_turns = left > 0 && l <= follow, right_turns = right < 0 && r <= follow;
    if (left_turns && (!right_turns || l <= r)) return left;
    if (right_turns) return right;
  }
  return shared;
}

// Of the candidates, the one nearest `target` if it is within `tolerance` of it.
std::optional<double> NearestWithin(std::initializer_list<double> candidates, double target, double tolerance) {
  std::optional<double> nearest;
  for (double c : candidates)
    if (std::abs(c - target) <= tolerance && (!nearest || std::abs(c - target) < std::abs(*nearest - target)))
      nearest = c;
  return nearest;
}

// prefix[i] = sum of p[n] for n < i, in double: the sum over any overlap in O(1), to well under
// float precision.
void PrefixSums(std::span<const float> p, std::vector<double>& prefix) {
  prefix.resize(p.size() + 1);
  prefix[0] = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) prefix[i + 1] = prefix[i] + p[i];
}

// Sum of |a[n] - gain * b[n]| over n < count, in eight interleaved partial sums (two SSE2
// registers; the same order in a plain build) combined at the end, so every build computes the
// same float. Every 32 entries the running total is checked: once total / divisor > bound the
// sum is abandoned and a partial total (already > bound * divisor) returned. The terms are never
// negative, so the full sum is at least any partial total.
float AbsoluteDifferenceSum(const float* a, const float* b, float gain, int count, double divisor, double bound) {
  float lane[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  auto combined = [&lane] { return ((lane[0] + lane[4]) + (lane[1] + lane[5])) + ((lane[2] + lane[6]) + (lane[3] + lane[7])); };
  int n = 0;
#if defined(__SSE2__)
  const __m128 sign = _mm_set1_ps(-0.0f);
  const __m128 g = _mm_set1_ps(gain);
  __m128 low = _mm_setzero_ps();
  __m128 high = _mm_setzero_ps();
  while (n + 8 <= count) {
    const int stop = std::min(count - 7, n + 32);
    for (; n < stop; n += 8) {
      const __m128 d0 = _mm_sub_ps(_mm_loadu_ps(a + n), _mm_mul_ps(g, _mm_loadu_ps(b + n)));
      const __m128 d1 = _mm_sub_ps(_mm_loadu_ps(a + n + 4), _mm_mul_ps(g, _mm_loadu_ps(b + n + 4)));
      low = _mm_add_ps(low, _mm_andnot_ps(sign, d0));
      high = _mm_add_ps(high, _mm_andnot_ps(sign, d1));
    }
    _mm_storeu_ps(lane, low);
    _mm_storeu_ps(lane + 4, high);
    const float total = combined();
    if (static_cast<double>(total) / divisor > bound) return total;
  }
#else
  while (n + 8 <= count) {
    const int stop = std::min(count - 7, n + 32);
    for (; n < stop; n += 8) {
      for (int k = 0; k < 8; ++k) lane[k] += std::abs(a[n + k] - gain * b[n + k]);
    }
    const float total = combined();
    if (static_cast<double>(total) / divisor > bound) return total;
  }
#endif
  float sum = combined();
  for (; n < count; ++n) sum += std::abs(a[n] - gain * b[n]);
  return sum;
}

// f(shift) of eq. 4 (see ShiftedProfileDifference) from the profiles and their prefix sums, or
// some value > bound once it is certain to exceed bound.
double DifferenceAt(std::span<const float> current, std::span<const float> previous, const std::vector<double>& prefix_current,
                    const std::vector<double>& prefix_previous, int shift, bool match_gain,
                    double bound = std::numeric_limits<double>::infinity()) {
  const int w = static_cast<int>(current.size());
  const int overlap = w - std::abs(shift);
  const int start_a = std::max(shift, 0);
  const int start_b = -std::min(shift, 0);
  float gain = 1.0f;
  if (match_gain) {
    const double sum_a = prefix_current[start_a + overlap] - prefix_current[start_a];
    const double sum_b = prefix_previous[start_b + overlap] - prefix_previous[start_b];
    // A black overlap has no exposure to match.
    if (sum_b > 1e-6 && sum_a > 1e-6) gain = static_cast<float>(sum_a / sum_b);
  }
  const float sum =
      AbsoluteDifferenceSum(current.data() + start_a, previous.data() + start_b, gain, overlap, overlap, bound);
  return static_cast<double>(sum) / overlap;
}

}  // namespace

double ShiftedProfileDifference(std::span<const float> current, std::span<const float> previous, int shift,
                                bool match_gain) {
  const int w = static_cast<int>(current.size());
  if (previous.size() != current.size()) throw std::invalid_argument("profiles differ in length");
  if (std::abs(shift) >= w) throw std::invalid_argument("shift leaves no overlap");
  std::vector<double> prefix_current, prefix_previous;
  PrefixSums(current, prefix_current);
  PrefixSums(previous, prefix_previous);
  return DifferenceAt(current, previous, prefix_current, prefix_previous, shift, match_gain);
}

int LargestSearchedShift(int width, int max_shift, int min_overlap) {
  return std::max(std::min(max_shift, width - min_overlap - 1), 0);
}

ProfileMatch BestProfileShift(std::span<const float> current, std::span<const float> previous, int max_shift,
                              int min_overlap, bool match_gain) {
  const int w = static_cast<int>(current.size());
  if (previous.size() != current.size()) throw std::invalid_argument("profiles differ in length");
  if (w == 0) throw std::invalid_argument("shift leaves no overlap");
  std::vector<double> prefix_current, prefix_previous;
  PrefixSums(current, prefix_current);
  PrefixSums(previous, prefix_previous);
  ProfileMatch best{0, DifferenceAt(current, previous, prefix_current, prefix_previous, 0, match_gain)};
  const int largest = LargestSearchedShift(w, max_shift, min_overlap);
  for (int magnitude = 1; magnitude <= largest; ++magnitude) {
    for (int shift : {magnitude, -magnitude}) {
      // Abandoned once certainly not below the best: only a strictly smaller f wins.
      const double f = DifferenceAt(current, previous, prefix_current, prefix_previous, shift, match_gain,
                                    best.difference);
      if (f < best.difference) best = {shift, f};
    }
  }
  return best;
}

namespace {

// sums[x] = sum over `rows` rows of row[x] for x in [x0, width), 16 columns at a time in 16-bit
// SSE2 lanes (exact for up to 257 rows; more rows fall to the plain loop). Returns where it
// stopped.
int ColumnSumsSse2(const uint8_t* first, std::size_t stride, int rows, int x0, int width, uint32_t* sums) {
#if defined(__SSE2__)
  if (rows <= 257) {
    const __m128i zero = _mm_setzero_si128();
    for (; x0 + 16 <= width; x0 += 16) {
      __m128i low = zero, high = zero;
      const uint8_t* p = first + x0;
      for (int y = 0; y < rows; ++y, p += stride) {
        const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
        low = _mm_add_epi16(low, _mm_unpacklo_epi8(v, zero));
        high = _mm_add_epi16(high, _mm_unpackhi_epi8(v, zero));
      }
      _mm_storeu_si128(reinterpret_cast<__m128i*>(sums + x0), _mm_unpacklo_epi16(low, zero));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(sums + x0 + 4), _mm_unpackhi_epi16(low, zero));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(sums + x0 + 8), _mm_unpacklo_epi16(high, zero));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(sums + x0 + 12), _mm_unpackhi_epi16(high, zero));
    }
  }
#endif
  return x0;
}

#if defined(__x86_64__)
// The same, 32 columns at a time (AVX2), then 16 at a time.
__attribute__((target("avx2"))) int ColumnSumsAvx2(const uint8_t* first, std::size_t stride, int rows, int x0,
                                                   int width, uint32_t* sums) {
  if (rows <= 257) {
    for (; x0 + 32 <= width; x0 += 32) {
      __m256i low = _mm256_setzero_si256(), high = _mm256_setzero_si256();
      const uint8_t* p = first + x0;
      for (int y = 0; y < rows; ++y, p += stride) {
        low = _mm256_add_epi16(low, _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))));
        high = _mm256_add_epi16(high, _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16))));
      }
      for (int half = 0; half < 2; ++half) {
        const __m256i v = half == 0 ? low : high;
        uint32_t* out = sums + x0 + 16 * half;
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), _mm256_cvtepu16_epi32(_mm256_castsi256_si128(v)));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + 8), _mm256_cvtepu16_epi32(_mm256_extracti128_si256(v, 1)));
      }
    }
  }
  return ColumnSumsSse2(first, stride, rows, x0, width, sums);
}
#endif

}  // namespace

void ColumnIntensityProfile(const cv::Mat& grey, const cv::Rect& crop, std::vector<float>& profile) {
  profile.resize(crop.width);
  std::vector<uint32_t> sums(crop.width, 0);
  const uint8_t* first = grey.ptr<uint8_t>(crop.y) + crop.x;
  const std::size_t stride = grey.step[0];
#if defined(__x86_64__)
  static const bool avx2 = [] {  // decided once; the project is not built for a particular CPU
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  const int x0 = avx2 ? ColumnSumsAvx2(first, stride, crop.height, 0, crop.width, sums.data())
                      : ColumnSumsSse2(first, stride, crop.height, 0, crop.width, sums.data());
#else
  const int x0 = ColumnSumsSse2(first, stride, crop.height, 0, crop.width, sums.data());
#endif
  for (int y = 0; y < crop.height; ++y) {
    const uint8_t* row = first + y * stride;
    for (int x = x0; x < crop.width; ++x) sums[x] += row[x];
  }
  const float scale = 1.0f / (255.0f * static_cast<float>(crop.height));
  for (int x = 0; x < crop.width; ++x) profile[x] = static_cast<float>(sums[x]) * scale;
}

VisualOdometry::VisualOdometry(VisualOdometryConfig config) : config_(std::move(config)) { config_.Validate(); }

void VisualOdometry::Reset() {
  has_previous_ = false;
  turning_shift_px_.reset();
  turning_shift_before_px_.reset();
  agreed_turn_shift_px_.reset();
  image_size_ = cv::Size(0, 0);
}

void VisualOdometry::CheckImage(const cv::Mat& image) const {
  if (image.empty()) throw std::invalid_argument("VisualOdometry: empty image");
  if (image.type() != CV_8UC1 && image.type() != CV_8UC3 && image.type() != CV_8UC4) {
    throw std::invalid_argument("VisualOdometry: image must be CV_8UC1 (grey), CV_8UC3 (BGR) or CV_8UC4 (BGRA), got type " +
                                std::to_string(image.type()));
  }
  if (has_previous_ && image.size() != image_size_) {
    throw std::invalid_argument("VisualOdometry: image size changed from " + std::to_string(image_size_.width) +
                                "x" + std::to_string(image_size_.height) + " to " +
                                std::to_string(image.cols) + "x" + std::to_string(image.rows));
  }
}

cv::Mat VisualOdometry::GreyCrop(const cv::Mat& image, const cv::Rect& crop) {
  if (image.channels() == 1) return image(crop);  // a view, no copy
  // Grey conversion is per pixel, so converting only the crop gives the crop of the converted
  // frame, bit for bit, at a fraction of the cost.
  cv::cvtColor(image(crop), crop_grey_, image.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  return crop_grey_;
}

void VisualOdometry::CropProfile(const cv::Mat& image, const cv::Rect& crop, std::vector<float>& profile) {
  ColumnIntensityProfile(GreyCrop(image, crop), cv::Rect(0, 0, crop.width, crop.height), profile);
}

namespace {

// Offset in (-0.5, 0.5) of the minimum of f around the integer best shift, by fitting a V (equal
// slopes) through f(s-1), f(s), f(s+1); 0 at the edge of the searched range.
double SubpixelOffset(std::span<const float> current, std::span<const float> previous, const ProfileMatch& best,
                      bool match_gain) {
  const int w = static_cast<int>(current.size());
  if (w - (std::abs(best.shift) + 1) < 1) return 0.0;
  std::vector<double> prefix_current, prefix_previous;
  PrefixSums(current, prefix_current);
  PrefixSums(previous, prefix_previous);
  const double left = DifferenceAt(current, previous, prefix_current, prefix_previous, best.shift - 1, match_gain);
  const double right = DifferenceAt(current, previous, prefix_current, prefix_previous, best.shift + 1, match_gain);
  const double centre = best.difference;
  const double slope = std::max(left, right) - centre;
  if (!(slope > 1e-12)) return 0.0;
  return std::clamp((left - right) / (2.0 * slope), -0.5, 0.5);
}

}  // namespace

EqualAngleColumns MakeEqualAngleColumns(cv::Size image, double fov_rad, double tilt_rad, const cv::Rect& crop) {
  if (crop.width < 2 || crop.height < 1 || crop.x < 0 || crop.y < 0 || crop.x + crop.width > image.width ||
      crop.y + crop.height > image.height || !(fov_rad > 0 && fov_rad < std::numbers::pi) ||
      !(std::abs(tilt_rad) < std::numbers::pi / 2)) {
    throw std::invalid_argument("MakeEqualAngleColumns: needs a crop of 2 or more columns inside the image, a field of "
                                "view in (0, pi) and a tilt under pi/2");
  }
  const double focal = 0.5 * image.width / std::tan(0.5 * fov_rad);
  const auto x_of = [&](double u) { return (u + 0.5 - 0.5 * image.width) / focal; };
  std::vector<double> forward(static_cast<size_t>(crop.height));
  double low = -std::numbers::pi, high = std::numbers::pi;
  for (int r = 0; r < crop.height; ++r) {
    const double y = (crop.y + r + 0.5 - 0.5 * image.height) / focal;
    forward[static_cast<size_t>(r)] = std::cos(tilt_rad) - y * std::sin(tilt_rad);
    low = std::max(low, std::atan(x_of(crop.x) / forward[static_cast<size_t>(r)]));
    high = std::min(high, std::atan(x_of(crop.x + crop.width - 1) / forward[static_cast<size_t>(r)]));
  }
  EqualAngleColumns columns;
  columns.count = crop.width;
  columns.rad_per_column = (high - low) / (crop.width - 1);
  columns.at_px.resize(static_cast<size_t>(crop.height) * crop.width);
  for (int r = 0; r < crop.height; ++r) {
    for (int j = 0; j < crop.width; ++j) {
      const double x = forward[static_cast<size_t>(r)] * std::tan(low + j * columns.rad_per_column);
      const double u = x * focal + 0.5 * image.width - 0.5 - crop.x;
      columns.at_px[static_cast<size_t>(r) * crop.width + j] = std::clamp(u, 0.0, crop.width - 1.0);
    }
  }
  return columns;
}

void EqualAngleProfile(const cv::Mat& grey_crop, const EqualAngleColumns& columns, std::vector<float>& profile) {
  if (grey_crop.type() != CV_8UC1 || grey_crop.cols != columns.count ||
      columns.at_px.size() != static_cast<size_t>(grey_crop.rows) * columns.count) {
    throw std::invalid_argument("EqualAngleProfile: the crop does not match its columns");
  }
  std::vector<double> sums(static_cast<size_t>(columns.count), 0.0);
  const int last = columns.count - 1;
  for (int r = 0; r < grey_crop.rows; ++r) {
    const uint8_t* row = grey_crop.ptr<uint8_t>(r);
    const double* at = columns.at_px.data() + static_cast<size_t>(r) * columns.count;
    for (int j = 0; j < columns.count; ++j) {
      const int i = std::min(static_cast<int>(at[j]), last - 1);
      const double t = at[j] - i;
      sums[static_cast<size_t>(j)] += (1.0 - t) * row[i] + t * row[i + 1];
    }
  }
  profile.resize(sums.size());
  const double scale = 1.0 / (255.0 * grey_crop.rows);
  for (size_t j = 0; j < sums.size(); ++j) profile[j] = static_cast<float>(sums[j] * scale);
}

namespace {

// Each entry replaced by the mean of the entries within `radius` of it (fewer at the ends): a box
// filter, which moves with the profile, so a turn's shift is kept.
void SmoothProfile(std::vector<float>& profile, int radius) {
  if (radius <= 0 || profile.empty()) return;
  std::vector<double> prefix;
  PrefixSums(profile, prefix);
  const int n = static_cast<int>(profile.size());
  for (int i = 0; i < n; ++i) {
    const int lo = std::max(i - radius, 0), hi = std::min(i + radius + 1, n);
    profile[i] = static_cast<float>((prefix[hi] - prefix[lo]) / (hi - lo));
  }
}

}  // namespace

void VisualOdometry::RotationProfile(const cv::Mat& image, std::vector<float>& profile) {
  if (equal_angle_.count == 0) CropProfile(image, vrot_crop_, profile);
  else EqualAngleProfile(GreyCrop(image, vrot_crop_), equal_angle_, profile);
  SmoothProfile(profile, config_.rotation_profile_smoothing_px);
}

Velocity VisualOdometry::Update(const cv::Mat& image, double dt_s) {
  CheckImage(image);
  if (!std::isfinite(dt_s) || dt_s <= 0.0) {
    throw std::invalid_argument("VisualOdometry: dt must be finite and > 0, got " + std::to_string(dt_s));
  }
  if (!has_previous_) {
    const cv::Size size = image.size();
    const cv::Rect vtrans_crop = ResolveCrop(config_.vtrans_image_x_min, config_.vtrans_image_x_max,
                                             config_.vtrans_image_y_min, config_.vtrans_image_y_max, size, "vtrans");
    const cv::Rect vrot_crop = ResolveCrop(config_.vrot_image_x_min, config_.vrot_image_x_max,
                                           config_.vrot_image_y_min, config_.vrot_image_y_max, size, "vrot");
    const auto require_wider = [&](int width, const std::string& what) {
      if (width <= config_.min_overlap_px) {
        throw std::invalid_argument("VisualOdometry: " + what + " width " + std::to_string(width) +
                                    " must exceed min_overlap_px " + std::to_string(config_.min_overlap_px));
      }
    };
    require_wider(vtrans_crop.width, "crop");
    if (config_.rotation_from_halves) require_wider(vrot_crop.width / 2, "half the rotation crop's");
    else require_wider(vrot_crop.width, "crop");
    image_size_ = size;
    vtrans_crop_ = vtrans_crop;
    vrot_crop_ = vrot_crop;
    const double fov_rad = config_.camera_fov_deg * std::numbers::pi / 180.0;
    equal_angle_ = {};
    rad_per_column_ = fov_rad / size.width;
    if (config_.equal_angle_columns) {
      equal_angle_ = MakeEqualAngleColumns(size, fov_rad, config_.camera_tilt_rad, vrot_crop);
      rad_per_column_ = equal_angle_.rad_per_column;
    }
    CropProfile(image, vtrans_crop_, vtrans_previous_);
    RotationProfile(image, vrot_previous_);
    has_previous_ = true;
    return Velocity{};
  }

  CropProfile(image, vtrans_crop_, vtrans_profile_);
  RotationProfile(image, vrot_profile_);
  // The rotation profile's shift (refined below a pixel with subpixel_rotation) over [first, first + width).
  const auto rotation_shift = [&](size_t first, size_t width) {
    const std::span<const float> current(vrot_profile_.data() + first, width);
    const std::span<const float> previous(vrot_previous_.data() + first, width);
    const ProfileMatch match = BestProfileShift(current, previous, config_.max_shift_px, config_.min_overlap_px,
                                                config_.normalise_profile_brightness);
    if (config_.edge_shift_reads_no_turn && match.shift != 0 &&
        std::abs(match.shift) == LargestSearchedShift(static_cast<int>(width), config_.max_shift_px, config_.min_overlap_px))
      return std::pair{0, 0.0};
    double shift = match.shift;
    if (config_.subpixel_rotation)
      shift += SubpixelOffset(current, previous, match, config_.normalise_profile_brightness);
    return std::pair{match.shift, shift};
  };
  const size_t rotation_width = vrot_profile_.size();
  std::pair<int, double> rotation;
  bool halves_agree = false;
  if (config_.rotation_from_halves) {
    const size_t half = rotation_width / 2;
    const auto left = rotation_shift(0, half), right = rotation_shift(rotation_width - half, half);
    double shared = HalvesShift(left.second, right.second, turning_shift_px_, turning_shift_before_px_,
                                config_.turn_continuity_px, config_.turn_follow_px,
                                config_.turn_continuity_forward_px);
    halves_agree = std::abs(left.second - right.second) <= config_.turn_continuity_px;
    if (config_.turn_continuity_agreed_rate && !halves_agree && agreed_turn_shift_px_) {
      const double whole = rotation_shift(0, rotation_width).second;
      if (const auto nearest = NearestWithin({left.second, right.second, whole}, *agreed_turn_shift_px_,
                                             config_.turn_continuity_px))
        shared = *nearest;
    }
    rotation = {static_cast<int>(std::lround(shared)), shared};
  } else {
    rotation = rotation_shift(0, rotation_width);
  }
  const ProfileMatch speed =
      BestProfileShift(vtrans_profile_, vtrans_previous_, config_.max_shift_px, config_.min_overlap_px,
                       config_.normalise_profile_brightness);
  std::swap(vtrans_profile_, vtrans_previous_);
  std::swap(vrot_profile_, vrot_previous_);

  Velocity velocity;
  velocity.rotation_shift_px = rotation.first;
  velocity.vrot = rotation.second * rad_per_column_ / dt_s;
  velocity.speed_difference = speed.difference;
  const double moving_difference = std::max(speed.difference - config_.vtrans_noise_floor, 0.0);
  velocity.vtrans =
      std::min(moving_difference * config_.vtrans_scaling / (config_.camera_hz * dt_s), config_.vtrans_max);
  const bool turning =
      config_.turn_in_place_vrot_radps > 0 && std::abs(velocity.vrot) >= config_.turn_in_place_vrot_radps;
  if (turning) velocity.vtrans = 0.0;
  turning_shift_before_px_ = turning_shift_px_;
  turning_shift_px_ = turning ? std::optional<double>(rotation.second) : std::nullopt;
  // Halves agreeing on another rate (a turn's last, partial frame) end the turn's rate.
  const bool rate_changed = halves_agree && agreed_turn_shift_px_ &&
                            std::abs(rotation.second - *agreed_turn_shift_px_) > config_.turn_continuity_px;
  if (!turning || rate_changed) agreed_turn_shift_px_.reset();
  else if (halves_agree) agreed_turn_shift_px_ = rotation.second;
  return velocity;
}

}  // namespace rslam::odometry
