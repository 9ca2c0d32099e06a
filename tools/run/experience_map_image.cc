#include "tools/run/experience_map_image.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <string>

#include "tools/run/plot_axes.h"

namespace rslam::run {

cv::Mat DrawExperienceMap(const experience_map::ExperienceMap& map,
                          const std::set<std::pair<uint32_t, uint32_t>>& loop_closure_links, cv::Size size) {
  const auto& experiences = map.experiences();
  PlotRange x{0.0, 0.0}, y{0.0, 0.0};
  if (!experiences.empty()) {
    x = {experiences[0].x_m, experiences[0].x_m};
    y = {experiences[0].y_m, experiences[0].y_m};
    for (const auto& e : experiences) {
      x = {std::min(x.min, e.x_m), std::max(x.max, e.x_m)};
      y = {std::min(y.min, e.y_m), std::max(y.max, e.y_m)};
    }
    // 5% margin so dots on the edge stay inside the frame.
    const double pad = 0.05 * std::max({x.max - x.min, y.max - y.min, 1e-3});
    x = {x.min - pad, x.max + pad};
    y = {y.min - pad, y.max + pad};
  }
  const PlotAxes axes(size, x, y, /*equal_scale=*/true);
  const std::string title = "experience map: " + std::to_string(experiences.size()) + " experiences, " +
                            std::to_string(map.links().size()) + " links, " +
                            std::to_string(loop_closure_links.size()) + " loop closures";
  cv::Mat image = axes.DrawFrame(title, "x (m)", "y (m)");
  cv::Mat plot = image(axes.area());
  const cv::Point offset = axes.area().tl();
  auto at = [&](const experience_map::Experience& e) { return axes.ToPixelInt(e.x_m, e.y_m) - offset; };

  const cv::Scalar link_colour(200, 140, 60), closure_colour(40, 40, 220);
  for (const auto& link : map.links()) {
    const bool closure = loop_closure_links.count({link.from_id, link.to_id}) > 0;
    if (!closure)
      cv::line(plot, at(experiences[link.from_id]), at(experiences[link.to_id]), link_colour, 1, cv::LINE_AA);
  }
  for (const auto& link : map.links()) {
    if (loop_closure_links.count({link.from_id, link.to_id})) {
      cv::line(plot, at(experiences[link.from_id]), at(experiences[link.to_id]), closure_colour, 2, cv::LINE_AA);
    }
  }
  const int radius = experiences.size() > 2000 ? 1 : 2;
  for (const auto& e : experiences) cv::circle(plot, at(e), radius, cv::Scalar(120, 40, 20), cv::FILLED, cv::LINE_AA);
  if (!experiences.empty()) {
    cv::circle(plot, at(experiences.front()), 6, cv::Scalar(40, 170, 40), 2, cv::LINE_AA);
    if (map.has_current())
      cv::circle(plot, at(experiences[map.current_id()]), 6, cv::Scalar(0, 140, 255), 2, cv::LINE_AA);
  }
  // Legend.
  const int fx = axes.area().x + 10, fy = axes.area().y + 18;
  auto legend = [&](int row, const cv::Scalar& colour, const std::string& text, int line_width = 0) {
    if (line_width > 0) {
      cv::line(image, {fx - 6, fy + 18 * row - 4}, {fx + 6, fy + 18 * row - 4}, colour, line_width, cv::LINE_AA);
    } else {
      cv::circle(image, {fx, fy + 18 * row - 4}, 5, colour, 2, cv::LINE_AA);
    }
    cv::putText(image, text, {fx + 12, fy + 18 * row}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(40, 40, 40), 1,
                cv::LINE_AA);
  };
  legend(0, cv::Scalar(40, 170, 40), "first experience");
  legend(1, cv::Scalar(0, 140, 255), "current experience");
  legend(2, link_colour, "link", 1);
  legend(3, closure_colour, "loop closure link", 2);
  return image;
}

}  // namespace rslam::run
