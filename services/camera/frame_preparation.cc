#include "services/camera/frame_preparation.h"

#include <opencv2/imgproc.hpp>

#include <stdexcept>
#include <string>

namespace rslam::camera {
namespace {

std::unique_ptr<const occupancy::CameraModel> MakeModel(const CameraNodeConfig& config) {
  if (!config.anti_vignetting && !config.undistort) return nullptr;
  try {
    return std::make_unique<const occupancy::CameraModel>(config.model);
  } catch (const ConfigError& e) {
    throw ConfigError("model." + e.key(), e.reason());
  }
}

}  // namespace

FramePreparation::FramePreparation(const CameraNodeConfig& config)
    : crop_(config.crop),
      grey_(config.grey),
      anti_vignetting_(config.anti_vignetting),
      undistort_(config.undistort),
      model_(MakeModel(config)) {}

cv::Mat FramePreparation::Apply(const cv::Mat& raw) const {
  if (raw.empty() || raw.depth() != CV_8U || (raw.channels() != 1 && raw.channels() != 3))
    throw std::invalid_argument("frame is not an 8-bit image with 1 or 3 channels");
  cv::Mat image = raw;
  if (model_) {
    if (image.cols != model_->config().width || image.rows != model_->config().height)
      throw std::invalid_argument("frame is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                  ", the camera model (model.width/height) is " +
                                  std::to_string(model_->config().width) + "x" +
                                  std::to_string(model_->config().height));
    if (anti_vignetting_) image = model_->CorrectVignetting(image);
    if (undistort_) image = model_->Undistort(image);
  }
  if (crop_.active()) {
    const int width = crop_.width > 0 ? crop_.width : image.cols - crop_.x;
    const int height = crop_.height > 0 ? crop_.height : image.rows - crop_.y;
    if (width <= 0 || height <= 0 || crop_.x + width > image.cols || crop_.y + height > image.rows)
      throw std::invalid_argument("crop (" + std::to_string(crop_.x) + ", " + std::to_string(crop_.y) + ") " +
                                  std::to_string(crop_.width) + "x" + std::to_string(crop_.height) +
                                  " does not lie inside the " + std::to_string(image.cols) + "x" +
                                  std::to_string(image.rows) + " frame");
    image = image(cv::Rect(crop_.x, crop_.y, width, height));
  }
  if (grey_ && image.channels() == 3) {
    cv::Mat grey;
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
    image = grey;
  }
  return image;
}

}  // namespace rslam::camera
