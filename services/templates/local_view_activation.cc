#include "services/templates/local_view_activation.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rslam::templates {

std::vector<double> LocalViewActivation(std::span<const double> differences, double d_max, double eps) {
  if (!(eps > 0.0) || !std::isfinite(eps)) throw std::invalid_argument("LocalViewActivation: eps must be finite and > 0");
  if (std::isnan(d_max)) throw std::invalid_argument("LocalViewActivation: d_max is NaN");
  std::vector<double> activation(differences.size(), 0.0);
  double total = 0.0;
  for (std::size_t i = 0; i < differences.size(); ++i) {
    const double d = differences[i];
    if (std::isnan(d) || d < 0.0) {
      throw std::invalid_argument("LocalViewActivation: difference " + std::to_string(i) + " is NaN or negative");
    }
    if (d <= d_max) {
      activation[i] = 1.0 / (d + eps);
      total += activation[i];
    }
  }
  if (total > 0.0) {
    for (double& v : activation) v /= total;
  }
  return activation;
}

}  // namespace rslam::templates
