#pragma once
// Floor segmentation of paper 003, section 3: Canny edges, then a flood fill from the bottom of
// the image upwards that stops at edges and at pixels whose colour differs from the learned floor
// colour by more than a tolerance. The seed is the bottom-centre pixel; if its colour is not the
// floor's (an obstacle right in front of the robot), the bottom row is searched outwards from
// the centre for a floor-coloured pixel, so the fill never starts inside an obstacle. If no row
// near the bottom has floor colour, the obstacle fills the view and the mask is empty. Edge
// pixels of the floor's colour next to the filled floor are floor too: Canny puts a colour step's
// edge on either side of it, and on the floor's side the fill would stop a row short.

#include <opencv2/core.hpp>
#include <optional>

#include "common/config/config_error.h"

namespace rslam::occupancy {

struct FloorSegmenterConfig {
  int blur_kernel = 3;           // Gaussian low-pass before Canny (Horswill's texture constraint)
  double canny_low = 40.0;
  double canny_high = 120.0;
  int colour_tolerance = 30;     // max per-channel difference from the floor colour
  double seed_search_rows_fraction = 0.05;  // rows above the bottom also searched for a seed

  template <class V>
  void VisitFields(V& v) {
    v("blur_kernel", blur_kernel, "odd Gaussian kernel size before Canny (1 = none)");
    v("canny_low", canny_low, "Canny lower hysteresis threshold");
    v("canny_high", canny_high, "Canny upper hysteresis threshold");
    v("colour_tolerance", colour_tolerance, "max per-channel difference from the floor colour");
    v("seed_search_rows_fraction", seed_search_rows_fraction,
      "fraction of the image height, from the bottom, searched for a floor-coloured seed");
  }
  void Validate() const;
};

class FloorSegmenter {
 public:
  FloorSegmenter(FloorSegmenterConfig config, cv::Vec3b floor_colour_bgr);

  // The mean colour of a region known to be floor (the paper's initialisation sequence).
  static cv::Vec3b LearnFloorColour(const cv::Mat& bgr_image, const cv::Rect& floor_region);

  // Floor mask (CV_8U, 255 = floor, 0 = not floor) of a CV_8UC3 BGR image (a CV_8UC1 grey image is
  // compared with the floor colour's grey value). Throws std::invalid_argument on other input.
  cv::Mat Segment(const cv::Mat& image) const;

  // The seed pixel the fill would start from, or nothing when the obstacle fills the view.
  std::optional<cv::Point> FindSeed(const cv::Mat& floor_coloured) const;

  cv::Vec3b floor_colour() const { return floor_colour_; }

 private:
  const FloorSegmenterConfig config_;
  const cv::Vec3b floor_colour_;
};

}  // namespace rslam::occupancy
