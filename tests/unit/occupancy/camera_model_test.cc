#include "services/occupancy/camera_model.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

namespace rslam::occupancy {
namespace {

// A flat grey card seen through a lens that darkens each channel by 1 / (1 + k_c r^2).
cv::Mat VignettedFlatImage(const CameraModel& model, const std::vector<double>& k, double level) {
  const CameraConfig& c = model.config();
  cv::Mat image(c.height, c.width, CV_8UC3);
  for (int v = 0; v < c.height; ++v)
    for (int u = 0; u < c.width; ++u) {
      const double r2 = model.NormalisedRadiusSquared(u, v);
      for (int ch = 0; ch < 3; ++ch)
        image.at<cv::Vec3b>(v, u)[ch] = cv::saturate_cast<uchar>(level / (1.0 + k[ch] * r2));
    }
  return image;
}

TEST(CameraModelTest, VignettingCalibrationRecoversKnownGains) {
  const CameraModel model(CameraConfig{});
  const std::vector<double> truth = {0.45, 0.30, 0.15};  // B, G, R
  const std::vector<double> fitted = FitVignettingGains(VignettedFlatImage(model, truth, 220.0));
  ASSERT_EQ(fitted.size(), 3u);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(fitted[c], truth[c], 0.02) << "channel " << c;
}

TEST(CameraModelTest, AntiVignettingFlattensAFlatCard) {
  CameraConfig config;
  const std::vector<double> truth = {0.45, 0.30, 0.15};
  const CameraModel plain(config);
  const cv::Mat card = VignettedFlatImage(plain, truth, 200.0);
  config.vignetting_gains = FitVignettingGains(card);
  const CameraModel corrected(config);
  const cv::Mat flat = corrected.CorrectVignetting(card);
  cv::Mat diff;
  cv::absdiff(flat, cv::Scalar(200, 200, 200), diff);
  double worst = 0;
  cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
  EXPECT_LE(worst, 3.0);
  cv::absdiff(card, cv::Scalar(200, 200, 200), diff);
  cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
  EXPECT_GT(worst, 50.0);  // the corners really were dark before
}

TEST(CameraModelTest, UndistortionInvertsOpenCvDistortion) {
  CameraConfig config;
  config.k1 = -0.25;
  config.k2 = 0.05;
  const CameraModel model(config);
  // A vertical white line at u = 40 in the ideal image, drawn where the distorted lens puts it.
  cv::Mat distorted = cv::Mat::zeros(config.height, config.width, CV_8UC1);
  for (double v = 0; v < config.height; v += 0.25) {
    const double x = (40 - config.cx) / config.fx, y = (v - config.cy) / config.fy;
    const double r2 = x * x + y * y, f = 1 + config.k1 * r2 + config.k2 * r2 * r2;
    const int u_d = static_cast<int>(std::lround(config.cx + config.fx * x * f));
    const int v_d = static_cast<int>(std::lround(config.cy + config.fy * y * f));
    if (u_d >= 0 && v_d >= 0 && u_d < config.width && v_d < config.height) distorted.at<uchar>(v_d, u_d) = 255;
  }
  const cv::Mat straight = model.Undistort(distorted);
  // In every row of the middle of the image the line is back within a pixel of u = 40.
  for (int v = 40; v < 200; v += 20) {
    cv::Point peak;
    cv::minMaxLoc(straight.row(v), nullptr, nullptr, nullptr, &peak);
    EXPECT_NEAR(peak.x, 40, 1) << "row " << v;
  }
}

TEST(CameraModelTest, RejectsBadImagesAndConfig) {
  const CameraModel model(CameraConfig{});
  EXPECT_THROW(model.Correct(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(model.Correct(cv::Mat(10, 10, CV_8UC3)), std::invalid_argument);
  EXPECT_THROW(model.Correct(cv::Mat(240, 320, CV_32FC1)), std::invalid_argument);
  CameraConfig bad;
  bad.tilt_rad = -0.1;
  EXPECT_THROW(CameraModel{bad}, ConfigError);
  EXPECT_THROW(FitVignettingGains(cv::Mat()), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::occupancy
