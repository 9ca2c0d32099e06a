#pragma once
// A 2-D plot frame drawn with OpenCV: data ranges mapped to a pixel rectangle, axes with "nice"
// tick values (1, 2, 5 x 10^k), tick labels, axis labels and a title. Used by the run's images.

#include <opencv2/core.hpp>

#include <string>

namespace rslam::run {

struct PlotRange {
  double min = 0.0, max = 1.0;
};

// Step between ticks: 1, 2 or 5 x 10^k giving about `target` ticks over span (> 0).
double NiceTickStep(double span, int target);

class PlotAxes {
 public:
  // canvas: the whole image; the plot area leaves margins for labels. With equal_scale, one
  // data unit is the same number of pixels on both axes (maps) and the ranges grow to fit.
  PlotAxes(cv::Size canvas, PlotRange x, PlotRange y, bool equal_scale);

  cv::Point2d ToPixel(double x, double y) const;
  cv::Point ToPixelInt(double x, double y) const;
  // White background, grid, ticks, tick labels, axis labels, title.
  cv::Mat DrawFrame(const std::string& title, const std::string& x_label, const std::string& y_label) const;

  const cv::Rect& area() const { return area_; }
  const PlotRange& x_range() const { return x_; }
  const PlotRange& y_range() const { return y_; }

 private:
  const cv::Size canvas_;
  const cv::Rect area_;
  PlotRange x_;
  PlotRange y_;
};

}  // namespace rslam::run
