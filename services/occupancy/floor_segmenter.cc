#include "services/occupancy/floor_segmenter.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace rslam::occupancy {

void FloorSegmenterConfig::Validate() const {
  Require(blur_kernel >= 1 && blur_kernel % 2 == 1 && blur_kernel <= 31, "blur_kernel",
          "must be odd, 1..31");
  Require(std::isfinite(canny_low) && canny_low >= 0, "canny_low", "must be >= 0");
  Require(std::isfinite(canny_high) && canny_high >= canny_low, "canny_high", "must be >= canny_low");
  Require(colour_tolerance >= 0 && colour_tolerance <= 255, "colour_tolerance", "must be 0..255");
  Require(std::isfinite(seed_search_rows_fraction) && seed_search_rows_fraction >= 0 &&
              seed_search_rows_fraction <= 1,
          "seed_search_rows_fraction", "must be in [0, 1]");
}

FloorSegmenter::FloorSegmenter(FloorSegmenterConfig config, cv::Vec3b floor_colour_bgr)
    : config_(std::move(config)), floor_colour_(floor_colour_bgr) {
  config_.Validate();
}

cv::Vec3b FloorSegmenter::LearnFloorColour(const cv::Mat& bgr_image, const cv::Rect& floor_region) {
  if (bgr_image.empty() || bgr_image.type() != CV_8UC3)
    throw std::invalid_argument("floor colour is learned from an 8-bit BGR image");
  const cv::Rect clipped = floor_region & cv::Rect(0, 0, bgr_image.cols, bgr_image.rows);
  if (clipped.area() == 0) throw std::invalid_argument("floor region lies outside the image");
  const cv::Scalar mean = cv::mean(bgr_image(clipped));
  return cv::Vec3b(cv::saturate_cast<uchar>(mean[0]), cv::saturate_cast<uchar>(mean[1]),
                   cv::saturate_cast<uchar>(mean[2]));
}

std::optional<cv::Point> FloorSegmenter::FindSeed(const cv::Mat& floor_coloured) const {
  const int rows_to_search =
      std::max(1, static_cast<int>(std::lround(config_.seed_search_rows_fraction * floor_coloured.rows)));
  const int centre = floor_coloured.cols / 2;
  for (int r = 0; r < rows_to_search && r < floor_coloured.rows; ++r) {
    const uchar* row = floor_coloured.ptr<uchar>(floor_coloured.rows - 1 - r);
    // Outwards from the centre, alternating right and left, so the seed nearest the robot's
    // heading wins.
    for (int d = 0; d <= centre + 1; ++d) {
      for (int u : {centre + d, centre - d}) {
        if (u >= 0 && u < floor_coloured.cols && row[u]) return cv::Point(u, floor_coloured.rows - 1 - r);
      }
    }
  }
  return std::nullopt;
}

cv::Mat FloorSegmenter::Segment(const cv::Mat& image) const {
  if (image.empty()) throw std::invalid_argument("image is empty");
  if (image.type() != CV_8UC3 && image.type() != CV_8UC1)
    throw std::invalid_argument("image must be 8-bit BGR or grey");
  cv::Mat grey;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY); else grey = image;
  cv::Mat smoothed = grey;
  if (config_.blur_kernel > 1)
    cv::GaussianBlur(grey, smoothed, cv::Size(config_.blur_kernel, config_.blur_kernel), 0);
  cv::Mat edges;
  cv::Canny(smoothed, edges, config_.canny_low, config_.canny_high);

  cv::Mat floor_coloured;
  const int tol = config_.colour_tolerance;
  if (image.channels() == 3) {
    const cv::Scalar lo(floor_colour_[0] - tol, floor_colour_[1] - tol, floor_colour_[2] - tol);
    const cv::Scalar hi(floor_colour_[0] + tol, floor_colour_[1] + tol, floor_colour_[2] + tol);
    cv::inRange(image, lo, hi, floor_coloured);
  } else {
    const double g = 0.114 * floor_colour_[0] + 0.587 * floor_colour_[1] + 0.299 * floor_colour_[2];
    cv::inRange(image, cv::Scalar(g - tol), cv::Scalar(g + tol), floor_coloured);
  }
  // Passable = floor coloured and not an edge. A 4-connected fill cannot cross an 8-connected
  // Canny contour, so the edges close the floor region.
  cv::Mat passable;
  cv::bitwise_and(floor_coloured, ~edges, passable);

  cv::Mat mask = cv::Mat::zeros(image.size(), CV_8U);
  const std::optional<cv::Point> seed = FindSeed(passable);
  if (!seed) return mask;  // the obstacle fills the view
  constexpr uchar kFilled = 128;
  cv::floodFill(passable, *seed, cv::Scalar(kFilled), nullptr, cv::Scalar(0), cv::Scalar(0), 4);
  cv::compare(passable, kFilled, mask, cv::CMP_EQ);
  // Canny marks a colour step on whichever side has the larger gradient; where that is the last
  // floor row the fill stopped a row short, and a row is 7 cm of floor 2.5 m away. An edge pixel
  // of the floor's colour next to the filled floor is floor.
  cv::Mat grown, floor_edges;
  cv::dilate(mask, grown, cv::getStructuringElement(cv::MORPH_CROSS, cv::Size(3, 3)));
  cv::bitwise_and(floor_coloured, edges, floor_edges);
  cv::bitwise_and(grown, floor_edges, grown);
  cv::bitwise_or(mask, grown, mask);
  return mask;
}

}  // namespace rslam::occupancy
