#pragma once
// One camera frame to one Radial Obstacle Profile, the chain of paper 003 sections 2.1 and 3:
// anti-vignetting and undistortion (CameraModel), floor segmentation (FloorSegmenter), and the
// profile read through the inverse perspective lookup (RopExtractor). Everything is precomputed
// at construction; ProfileFromImage does no allocation beyond the intermediate images.

#include <opencv2/core.hpp>
#include <vector>

#include "services/occupancy/camera_model.h"
#include "services/occupancy/floor_segmenter.h"
#include "services/occupancy/inverse_perspective_map.h"
#include "services/occupancy/radial_obstacle_profile.h"

namespace rslam::occupancy {

struct ObstacleProfileConfig {
  CameraConfig camera;
  FloorSegmenterConfig floor;
  RopConfig profile;
  std::vector<int> floor_colour_bgr = {90, 150, 70};
  bool correct_images = true;  // anti-vignetting + undistortion before segmentation

  template <class V>
  void VisitFields(V& v) {
    v("camera", camera, "camera intrinsics, distortion, mounting and vignetting");
    v("floor", floor, "floor segmentation");
    v("profile", profile, "radial obstacle profile");
    v("floor_colour_bgr", floor_colour_bgr, "learned floor colour (B, G, R)");
    v("correct_images", correct_images, "apply anti-vignetting and undistortion first");
  }
  void Validate() const;
};

class ObstacleProfilePipeline {
 public:
  explicit ObstacleProfilePipeline(ObstacleProfileConfig config);
  ObstacleProfilePipeline(const ObstacleProfilePipeline&) = delete;
  ObstacleProfilePipeline& operator=(const ObstacleProfilePipeline&) = delete;

  // Throws std::invalid_argument for an image that is empty, of the wrong size or type.
  RadialObstacleProfile ProfileFromImage(const cv::Mat& image) const;
  // The floor mask of the last step, for display and debugging.
  cv::Mat FloorMask(const cv::Mat& image) const;

  const InversePerspectiveMap& ipm() const { return ipm_; }

 private:
  const ObstacleProfileConfig config_;
  const CameraModel camera_;
  const InversePerspectiveMap ipm_;
  const FloorSegmenter segmenter_;
  const RopExtractor extractor_;
};

}  // namespace rslam::occupancy
