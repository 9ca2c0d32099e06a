#include "tools/eval/patch_normalised_sad.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <stdexcept>
#include <vector>

namespace rslam::eval {
namespace {

cv::Mat Ramp(int width, int height, int seed) {
  cv::Mat image(height, width, CV_8UC1);
  cv::RNG random(static_cast<uint64_t>(seed));
  random.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

TEST(PatchNormalisedSad, EachBlockHasZeroMeanAndUnitSpread) {
  const cv::Mat normalised = PatchNormalise(Ramp(16, 8, 1), 8);
  for (int x = 0; x < 16; x += 8) {
    cv::Scalar mean, spread;
    cv::meanStdDev(normalised(cv::Rect(x, 0, 8, 8)), mean, spread);
    EXPECT_NEAR(mean[0], 0.0, 1e-5);
    EXPECT_NEAR(spread[0], 1.0, 1e-5);
  }
}

TEST(PatchNormalisedSad, IgnoresBrightnessAndContrastChanges) {
  const cv::Mat summer = Ramp(64, 32, 2);
  cv::Mat winter;
  summer.convertTo(winter, CV_8U, 0.5, 100);  // darker contrast, brighter
  const std::vector<cv::Mat> references = {summer, Ramp(64, 32, 3)};
  const std::vector<cv::Mat> queries = {winter};
  const DifferenceMatrix d = BaselinePatchSad(references, queries);
  EXPECT_LT(d(0, 0), 0.05);
  EXPECT_GT(d(0, 1), 0.5);
}

TEST(PatchNormalisedSad, RejectsMismatchedOrEmptyImages) {
  const std::vector<cv::Mat> references = {Ramp(64, 32, 1)};
  const std::vector<cv::Mat> wrong_size = {Ramp(32, 32, 1)};
  EXPECT_THROW(BaselinePatchSad(references, wrong_size), std::invalid_argument);
  const std::vector<cv::Mat> empty = {cv::Mat()};
  EXPECT_THROW(BaselinePatchSad(references, empty), std::invalid_argument);
  EXPECT_THROW(BaselinePatchSad(references, {}), std::invalid_argument);
  EXPECT_THROW(PatchNormalise(cv::Mat(8, 8, CV_8UC3, cv::Scalar::all(1)), 8), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::eval
