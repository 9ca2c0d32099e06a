#pragma once
// Local-view cell activation (Prasser et al. 2004, paper 001 eq. 2):
//   V_i = 1 / (d_i + eps) if d_i <= d_max, else 0; then normalised so sum V_i = 1.
// d_i is the difference of the view to template i (TemplateLibrary::Differences).

#include <span>
#include <vector>

namespace rslam::templates {

// All zeros when no difference is <= d_max. Throws std::invalid_argument when eps <= 0, d_max
// is NaN, or a difference is NaN or negative.
std::vector<double> LocalViewActivation(std::span<const double> differences, double d_max, double eps);

}  // namespace rslam::templates
