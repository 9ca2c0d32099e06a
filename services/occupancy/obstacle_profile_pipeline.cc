#include "services/occupancy/obstacle_profile_pipeline.h"

namespace rslam::occupancy {

namespace {
cv::Vec3b ToColour(const std::vector<int>& bgr) {
  return cv::Vec3b(static_cast<uchar>(bgr.at(0)), static_cast<uchar>(bgr.at(1)), static_cast<uchar>(bgr.at(2)));
}
}  // namespace

void ObstacleProfileConfig::Validate() const {
  ValidateNested(camera, "camera");
  ValidateNested(floor, "floor");
  ValidateNested(profile, "profile");
  Require(floor_colour_bgr.size() == 3, "floor_colour_bgr", "needs 3 values (B, G, R)");
  for (int c : floor_colour_bgr) Require(c >= 0 && c <= 255, "floor_colour_bgr", "each must be 0..255");
}

ObstacleProfilePipeline::ObstacleProfilePipeline(ObstacleProfileConfig config)
    : config_((config.Validate(), std::move(config))),
      camera_(config_.camera),
      ipm_(config_.camera),
      segmenter_(config_.floor, ToColour(config_.floor_colour_bgr)),
      extractor_(config_.profile, ipm_) {}

cv::Mat ObstacleProfilePipeline::FloorMask(const cv::Mat& image) const {
  if (image.empty() || image.cols != config_.camera.width || image.rows != config_.camera.height)
    throw std::invalid_argument("image is empty or not of the configured camera size");
  return segmenter_.Segment(config_.correct_images ? camera_.Correct(image) : image);
}

RadialObstacleProfile ObstacleProfilePipeline::ProfileFromImage(const cv::Mat& image) const {
  return extractor_.Extract(FloorMask(image));
}

}  // namespace rslam::occupancy
