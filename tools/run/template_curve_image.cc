#include "tools/run/template_curve_image.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <string>

#include "tools/run/plot_axes.h"

namespace rslam::run {

cv::Mat DrawTemplateCurve(const std::vector<TemplateCurvePoint>& curve, cv::Size size) {
  const double frames = curve.empty() ? 1.0 : static_cast<double>(curve.back().frame + 1);
  const double templates = curve.empty() ? 1.0 : static_cast<double>(curve.back().template_count);
  const PlotAxes axes(size, {0.0, frames}, {0.0, templates * 1.05 + 1.0}, /*equal_scale=*/false);
  cv::Mat image = axes.DrawFrame("templates learnt: " + std::to_string(static_cast<long long>(templates)) + " over " +
                                     std::to_string(curve.size()) + " frames",
                                 "frame", "templates stored");
  const double top = templates * 1.05 + 1.0;
  // The diagonal "every frame is new" for reference: the gap to it is the recognised frames.
  cv::line(image, axes.ToPixelInt(0.0, 0.0), axes.ToPixelInt(std::min(frames, top), std::min(frames, top)),
           cv::Scalar(190, 190, 190), 1, cv::LINE_AA);
  std::vector<cv::Point> line;
  line.reserve(curve.size() + 1);
  line.push_back(axes.ToPixelInt(0.0, 0.0));
  for (const auto& p : curve) line.push_back(axes.ToPixelInt(static_cast<double>(p.frame + 1), p.template_count));
  cv::polylines(image, line, false, cv::Scalar(160, 60, 20), 2, cv::LINE_AA);
  const cv::Point legend = axes.area().tl() + cv::Point(12, 18);
  cv::line(image, legend + cv::Point(0, -4), legend + cv::Point(24, -4), cv::Scalar(160, 60, 20), 2, cv::LINE_AA);
  cv::putText(image, "templates stored", legend + cv::Point(30, 0), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
  cv::line(image, legend + cv::Point(0, 14), legend + cv::Point(24, 14), cv::Scalar(190, 190, 190), 1, cv::LINE_AA);
  cv::putText(image, "one new template per frame", legend + cv::Point(30, 18), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              cv::Scalar(40, 40, 40), 1, cv::LINE_AA);
  return image;
}

}  // namespace rslam::run
