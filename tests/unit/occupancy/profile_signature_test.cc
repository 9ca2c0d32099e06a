#include "services/occupancy/profile_signature.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace rslam::occupancy {
namespace {

// Range profile of a robot off-centre in a rectangular room: not symmetric, so rotations differ.
std::vector<float> RoomProfile(double cx, double cy) {
  std::vector<float> ranges(360);
  for (int i = 0; i < 360; ++i) {
    const double a = (i + 0.5) * M_PI / 180.0 - M_PI;
    const double c = std::cos(a), s = std::sin(a);
    double t = 1e9;
    if (c > 1e-9) t = std::min(t, (1.0 - cx) / c);
    if (c < -1e-9) t = std::min(t, (-1.0 - cx) / c);
    if (s > 1e-9) t = std::min(t, (0.6 - cy) / s);
    if (s < -1e-9) t = std::min(t, (-0.6 - cy) / s);
    ranges[i] = static_cast<float>(t);
  }
  return ranges;
}

TEST(ProfileSignatureTest, RotatedProfileKeepsItsInvariantSignatureButNotItsDct) {
  const std::vector<float> profile = RoomProfile(0.3, -0.1);
  std::vector<float> rotated = profile;
  std::rotate(rotated.begin(), rotated.begin() + 73, rotated.end());  // robot turned 73 degrees
  const auto inv_a = RotationInvariantSignature(profile, 20), inv_b = RotationInvariantSignature(rotated, 20);
  const auto dct_a = DctSignature(profile, 20), dct_b = DctSignature(rotated, 20);
  EXPECT_LT(SignatureDistance(inv_a, inv_b), 1e-4);
  EXPECT_GT(SignatureDistance(dct_a, dct_b), 0.05);
}

TEST(ProfileSignatureTest, DifferentPlacesHaveDifferentInvariantSignatures) {
  const auto here = RotationInvariantSignature(RoomProfile(0.3, -0.1), 20);
  const auto there = RotationInvariantSignature(RoomProfile(-0.6, 0.3), 20);
  EXPECT_GT(SignatureDistance(here, there), 0.02);
}

TEST(ProfileSignatureTest, DctFirstCoefficientIsTheMeanRange) {
  const std::vector<float> flat(360, 0.4f);
  const auto dct = DctSignature(flat, 20);
  EXPECT_NEAR(dct[0], 0.4f, 1e-5);
  for (int k = 1; k < 20; ++k) EXPECT_NEAR(dct[k], 0.0f, 1e-5);
}

TEST(ProfileSignatureTest, ProfileRangesFillsUnobservedBins) {
  RadialObstacleProfile p{-M_PI, M_PI, {RopBin{0.2f, 0.07f, BinStatus::kObstacle}, RopBin{}}};
  const auto ranges = ProfileRanges(p, 0.4f);
  EXPECT_FLOAT_EQ(ranges[0], 0.2f);
  EXPECT_FLOAT_EQ(ranges[1], 0.4f);
}

TEST(ProfileSignatureTest, RejectsBadInput) {
  EXPECT_THROW(DctSignature({}, 3), std::invalid_argument);
  const std::vector<float> r(10, 1.0f);
  EXPECT_THROW(DctSignature(r, 11), std::invalid_argument);
  const std::vector<float> bad = {1.0f, NAN};
  EXPECT_THROW(RotationInvariantSignature(bad, 1), std::invalid_argument);
  EXPECT_THROW(SignatureDistance(std::vector<float>(2), std::vector<float>(3)), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::occupancy
