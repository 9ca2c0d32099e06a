#include "services/templates/jeffrey_divergence.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rslam::templates {

double JeffreyDivergence(std::span<const float> h, std::span<const float> k) {
  if (h.size() != k.size()) throw std::invalid_argument("JeffreyDivergence: histograms differ in length");
  double d = 0.0;
  for (std::size_t i = 0; i < h.size(); ++i) {
    const double a = h[i];
    const double b = k[i];
    if (!std::isfinite(a) || !std::isfinite(b) || a < 0 || b < 0) {
      throw std::invalid_argument("JeffreyDivergence: histogram entries must be finite and >= 0");
    }
    if (a > 0) d += a * std::log(2.0 * a / (a + b));
    if (b > 0) d += b * std::log(2.0 * b / (a + b));
  }
  return d;
}

double JeffreySelfTerm(std::span<const float> h) {
  double s = 0.0;
  for (float v : h) {
    if (v > 0) s += v * std::log(2.0 * v);
  }
  return s;
}

double JeffreyDivergenceFromSelfTerms(std::span<const float> h, double self_h, std::span<const float> k,
                                      double self_k) {
  double cross = 0.0;
  for (std::size_t i = 0; i < h.size(); ++i) {
    const float sum = h[i] + k[i];
    if (sum > 0) cross += sum * std::log(sum);
  }
  // Rounding can leave a tiny negative value for identical histograms.
  return std::max(0.0, self_h + self_k - cross);
}

double JeffreyDivergenceLowerBound(std::span<const float> h, std::span<const float> k) {
  // Eight partial sums (the compiler vectorises them; the order does not matter for a bound
  // with a margin). A bin empty in both has h - k = 0: the denominator's floor keeps it 0 / tiny
  // = 0, and only lowers the terms of bins with h + k below it.
  constexpr float kFloor = 1e-30f;
  float partial[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  const std::size_t n = h.size();
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    for (std::size_t j = 0; j < 8; ++j) {
      const float difference = h[i + j] - k[i + j];
      partial[j] += difference * difference / std::max(h[i + j] + k[i + j], kFloor);
    }
  }
  for (; i < n; ++i) {
    const float difference = h[i] - k[i];
    partial[0] += difference * difference / std::max(h[i] + k[i], kFloor);
  }
  double discrimination = 0.0;
  for (float p : partial) discrimination += p;
  return std::max(0.0, 0.999 * discrimination / 2.0 - 1e-5);
}

}  // namespace rslam::templates
