#pragma once
// Place signatures from a 360-degree Radial Obstacle Profile (paper 003 section 5.3).
//  - DctSignature: the first K coefficients of the DCT-II of the range profile, the paper's
//    low-pass description (K = 20 in the paper). Heading-sensitive: rotating the robot shifts
//    the profile and changes the coefficients.
//  - RotationInvariantSignature: magnitudes |F_k| of the DFT of the circular profile for
//    k = 0..K-1. A rotation by whole bins is a circular shift, which changes only the phases, so
//    the signature does not depend on the robot's heading.
// Both are normalised by the number of bins. Unobserved and free bins count as fill_range_m,
// blind bins as their nearest visible range.

#include <span>
#include <vector>

#include "services/occupancy/radial_obstacle_profile.h"

namespace rslam::occupancy {

std::vector<float> ProfileRanges(const RadialObstacleProfile& profile, float fill_range_m);
std::vector<float> DctSignature(std::span<const float> ranges, int coefficients);
std::vector<float> RotationInvariantSignature(std::span<const float> ranges, int coefficients);
// Euclidean distance between two signatures of equal length (throws std::invalid_argument else).
float SignatureDistance(std::span<const float> a, std::span<const float> b);

}  // namespace rslam::occupancy
