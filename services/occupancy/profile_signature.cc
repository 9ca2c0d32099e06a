#include "services/occupancy/profile_signature.h"

#include <cmath>
#include <stdexcept>

namespace rslam::occupancy {

namespace {
void CheckInput(std::span<const float> ranges, int coefficients) {
  if (ranges.empty()) throw std::invalid_argument("profile has no bins");
  if (coefficients <= 0 || static_cast<size_t>(coefficients) > ranges.size())
    throw std::invalid_argument("signature length must be in 1..number of bins");
  for (float r : ranges)
    if (!std::isfinite(r)) throw std::invalid_argument("profile range is not finite");
}
}  // namespace

std::vector<float> ProfileRanges(const RadialObstacleProfile& profile, float fill_range_m) {
  std::vector<float> ranges(profile.bins.size(), fill_range_m);
  for (size_t i = 0; i < ranges.size(); ++i) {
    const RopBin& b = profile.bins[i];
    if (b.status == BinStatus::kObstacle) ranges[i] = b.range_m;
    else if (b.status == BinStatus::kBlind) ranges[i] = b.nearest_visible_m;
  }
  return ranges;
}

std::vector<float> DctSignature(std::span<const float> ranges, int coefficients) {
  CheckInput(ranges, coefficients);
  const size_t n = ranges.size();
  std::vector<float> out(coefficients);
  for (int k = 0; k < coefficients; ++k) {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += ranges[i] * std::cos(M_PI / n * (i + 0.5) * k);
    out[k] = static_cast<float>(sum / n);
  }
  return out;
}

std::vector<float> RotationInvariantSignature(std::span<const float> ranges, int coefficients) {
  CheckInput(ranges, coefficients);
  const size_t n = ranges.size();
  std::vector<float> out(coefficients);
  for (int k = 0; k < coefficients; ++k) {
    double re = 0.0, im = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double a = -2.0 * M_PI * static_cast<double>((k * i) % n) / n;
      re += ranges[i] * std::cos(a);
      im += ranges[i] * std::sin(a);
    }
    out[k] = static_cast<float>(std::hypot(re, im) / n);
  }
  return out;
}

float SignatureDistance(std::span<const float> a, std::span<const float> b) {
  if (a.size() != b.size()) throw std::invalid_argument("signatures differ in length");
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return static_cast<float>(std::sqrt(sum));
}

}  // namespace rslam::occupancy
