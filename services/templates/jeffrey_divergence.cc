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

}  // namespace rslam::templates
