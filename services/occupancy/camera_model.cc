#include "services/occupancy/camera_model.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace rslam::occupancy {

void CameraConfig::Validate() const {
  Require(width > 0 && width <= 8192, "width", "must be in 1..8192");
  Require(height > 0 && height <= 8192, "height", "must be in 1..8192");
  Require(std::isfinite(fx) && fx > 0, "fx", "must be positive");
  Require(std::isfinite(fy) && fy > 0, "fy", "must be positive");
  Require(std::isfinite(cx) && cx >= 0 && cx < width, "cx", "must lie inside the image");
  Require(std::isfinite(cy) && cy >= 0 && cy < height, "cy", "must lie inside the image");
  for (auto [k, name] : {std::pair{k1, "k1"}, {k2, "k2"}, {p1, "p1"}, {p2, "p2"}, {k3, "k3"}})
    Require(std::isfinite(k), name, "must be finite");
  Require(std::isfinite(height_m) && height_m > 0, "height_m", "must be positive");
  Require(std::isfinite(tilt_rad) && tilt_rad > 0 && tilt_rad < M_PI / 2, "tilt_rad",
          "must be in (0, pi/2): the camera must look down at the floor");
  Require(std::isfinite(forward_offset_m), "forward_offset_m", "must be finite");
  Require(vignetting_gains.size() == 3, "vignetting_gains", "needs 3 values (B, G, R)");
  for (double k : vignetting_gains)
    Require(std::isfinite(k) && k > -1.0, "vignetting_gains", "each must be finite and > -1");
}

CameraModel::CameraModel(CameraConfig config) : config_(std::move(config)) {
  config_.Validate();
  const cv::Matx33d k(config_.fx, 0, config_.cx, 0, config_.fy, config_.cy, 0, 0, 1);
  const cv::Vec<double, 5> dist(config_.k1, config_.k2, config_.p1, config_.p2, config_.k3);
  cv::initUndistortRectifyMap(k, dist, cv::noArray(), k, cv::Size(config_.width, config_.height),
                              CV_16SC2, undistort_map1_, undistort_map2_);
  gain_map_bgr_.create(config_.height, config_.width, CV_32FC3);
  gain_map_grey_.create(config_.height, config_.width, CV_32FC1);
  const double mean_k = (config_.vignetting_gains[0] + config_.vignetting_gains[1] +
                         config_.vignetting_gains[2]) / 3.0;
  for (int v = 0; v < config_.height; ++v) {
    auto* bgr = gain_map_bgr_.ptr<cv::Vec3f>(v);
    auto* grey = gain_map_grey_.ptr<float>(v);
    for (int u = 0; u < config_.width; ++u) {
      const double r2 = NormalisedRadiusSquared(u, v);
      for (int c = 0; c < 3; ++c) bgr[u][c] = static_cast<float>(1.0 + config_.vignetting_gains[c] * r2);
      grey[u] = static_cast<float>(1.0 + mean_k * r2);
    }
  }
}

double CameraModel::NormalisedRadiusSquared(double u, double v) const {
  const double cu = 0.5 * (config_.width - 1), cv_ = 0.5 * (config_.height - 1);
  const double half_diag2 = cu * cu + cv_ * cv_;
  return half_diag2 > 0 ? ((u - cu) * (u - cu) + (v - cv_) * (v - cv_)) / half_diag2 : 0.0;
}

void CameraModel::CheckImage(const cv::Mat& image) const {
  if (image.empty()) throw std::invalid_argument("camera image is empty");
  if (image.cols != config_.width || image.rows != config_.height)
    throw std::invalid_argument("camera image is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + ", expected " +
                                std::to_string(config_.width) + "x" + std::to_string(config_.height));
  if (image.type() != CV_8UC3 && image.type() != CV_8UC1)
    throw std::invalid_argument("camera image must be 8-bit BGR or grey");
}

cv::Mat CameraModel::CorrectVignetting(const cv::Mat& image) const {
  CheckImage(image);
  cv::Mat as_float, out;
  image.convertTo(as_float, image.channels() == 3 ? CV_32FC3 : CV_32FC1);
  cv::multiply(as_float, image.channels() == 3 ? gain_map_bgr_ : gain_map_grey_, as_float);
  as_float.convertTo(out, image.type());  // saturates at 255
  return out;
}

cv::Mat CameraModel::Undistort(const cv::Mat& image) const {
  CheckImage(image);
  cv::Mat out;
  cv::remap(image, out, undistort_map1_, undistort_map2_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

cv::Mat CameraModel::Correct(const cv::Mat& image) const { return Undistort(CorrectVignetting(image)); }

std::vector<double> FitVignettingGains(const cv::Mat& flat_image) {
  if (flat_image.empty()) throw std::invalid_argument("flat image is empty");
  if (flat_image.depth() != CV_8U || (flat_image.channels() != 1 && flat_image.channels() != 3))
    throw std::invalid_argument("flat image must be 8-bit grey or BGR");
  const int channels = flat_image.channels();
  const double cu = 0.5 * (flat_image.cols - 1), cv_ = 0.5 * (flat_image.rows - 1);
  const double half_diag2 = std::max(cu * cu + cv_ * cv_, 1e-12);
  // Normal equations of y = a + b x per channel, x = r^2, y = 1 / observed.
  std::vector<double> n(channels, 0), sx(channels, 0), sy(channels, 0), sxx(channels, 0),
      sxy(channels, 0);
  for (int v = 0; v < flat_image.rows; ++v) {
    const uchar* row = flat_image.ptr<uchar>(v);
    for (int u = 0; u < flat_image.cols; ++u) {
      const double x = ((u - cu) * (u - cu) + (v - cv_) * (v - cv_)) / half_diag2;
      for (int c = 0; c < channels; ++c) {
        const int value = row[u * channels + c];
        if (value == 0) continue;
        const double y = 1.0 / value;
        n[c] += 1; sx[c] += x; sy[c] += y; sxx[c] += x * x; sxy[c] += x * y;
      }
    }
  }
  std::vector<double> gains(channels, 0.0);
  for (int c = 0; c < channels; ++c) {
    const double det = n[c] * sxx[c] - sx[c] * sx[c];
    if (n[c] < 2 || std::abs(det) < 1e-12)
      throw std::invalid_argument("flat image has too few usable pixels to fit vignetting");
    const double b = (n[c] * sxy[c] - sx[c] * sy[c]) / det;
    const double a = (sy[c] - b * sx[c]) / n[c];
    gains[c] = b / a;
  }
  return gains;
}

}  // namespace rslam::occupancy
