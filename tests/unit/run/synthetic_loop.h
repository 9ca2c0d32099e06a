#pragma once
// Frames of a robot driving a closed loop, for tests: N places per lap, each frame the camera
// turns 360/N degrees and moves forward, so after N frames it is back at the first place and
// sees the first view again (frame i and frame i + N are identical images).
//
// The 640x480 BGR frame has three bands, each read by one stage (SyntheticLoopConfigYaml):
//   rows   0-160  a textured panorama scrolled by kScrollPx per frame: visual odometry rotation
//   rows 160-320  a texture unique to the place: the template library
//   rows 320-480  noise unique to the place: its change between frames is the odometry's speed

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdint>
#include <string>

namespace rslam::run::testing {

inline constexpr int kScrollPx = 20;

class SyntheticLoop {
 public:
  explicit SyntheticLoop(int places_per_lap) : places_(places_per_lap), panorama_(MakePanorama(places_per_lap)) {}

  int places_per_lap() const { return places_; }

  cv::Mat Frame(int index) const {
    const int place = index % places_;
    cv::Mat frame(480, 640, CV_8UC3);
    // Rotation band: the camera turns counter-clockwise, so the scene moves towards larger x.
    const int width = panorama_.cols;
    const int offset = ((-place * kScrollPx) % width + width) % width;
    cv::Mat band(160, 640, CV_8UC1);
    for (int x = 0; x < 640; ++x) panorama_.col((offset + x) % width).copyTo(band.col(x));
    cv::cvtColor(band, frame(cv::Rect(0, 0, 640, 160)), cv::COLOR_GRAY2BGR);
    cv::cvtColor(PlaceTexture(place), frame(cv::Rect(0, 160, 640, 160)), cv::COLOR_GRAY2BGR);
    cv::cvtColor(PlaceNoise(place), frame(cv::Rect(0, 320, 640, 160)), cv::COLOR_GRAY2BGR);
    return frame;
  }

  // A preset for these frames: crops on the three bands, a 320 degree lens so each frame's
  // 20 px scroll is a 10 degree turn (36 places per lap = one full turn).
  static std::string ConfigYaml() {
    return R"(odometry:
  vtrans_image_x_min: 40
  vtrans_image_x_max: 600
  vtrans_image_y_min: 330
  vtrans_image_y_max: 470
  vrot_image_x_min: 40
  vrot_image_x_max: 600
  vrot_image_y_min: 10
  vrot_image_y_max: 150
  camera_fov_deg: 320
  camera_hz: 10
templates:
  mode: patch
  image_crop_x_min: 40
  image_crop_x_max: 600
  image_crop_y_min: 170
  image_crop_y_max: 310
  template_x_size: 60
  template_y_size: 10
  normalisation: 0.4
  shift_match: 5
  crop_fov_deg: 280
  match_threshold: 0.085
pose_cells:
  pc_dim_xy: 21
experience_map:
  exp_loops: 10
)";
  }

 private:
  static cv::Mat Coarse(int width, int height, int cell, uint64_t seed, int low, int high) {
    cv::RNG rng(seed);
    cv::Mat coarse(height / cell + 1, width / cell + 1, CV_8UC1);
    rng.fill(coarse, cv::RNG::UNIFORM, low, high);
    cv::Mat fine;
    cv::resize(coarse, fine, cv::Size((width / cell + 1) * cell, (height / cell + 1) * cell), 0, 0, cv::INTER_LINEAR);
    return fine(cv::Rect(0, 0, width, height)).clone();
  }
  static cv::Mat MakePanorama(int places) { return Coarse(places * kScrollPx, 160, 8, 1234, 20, 235); }
  static cv::Mat PlaceTexture(int place) { return Coarse(640, 160, 16, 5000 + place, 20, 235); }
  static cv::Mat PlaceNoise(int place) {
    cv::RNG rng(9000 + place);
    cv::Mat noise(160, 640, CV_8UC1);
    rng.fill(noise, cv::RNG::UNIFORM, 70, 190);
    return noise;
  }

  const int places_;
  const cv::Mat panorama_;
};

}  // namespace rslam::run::testing
