#pragma once
// A configured image crop, as OpenRatSLAM's configs give them: columns [x_min, x_max) and rows
// [y_min, y_max) in pixels, where -1 as a maximum means the image's edge. Visual odometry, the
// template learner and `rslam run` (which converts only the rows the stages read) resolve their
// crops here, so they can never disagree about one.

#include <opencv2/core.hpp>

#include <optional>
#include <stdexcept>
#include <string>

namespace rslam {

// The crop on an image of `size`, or nothing when it does not fit inside it or is empty.
inline std::optional<cv::Rect> FitCrop(int x_min, int x_max, int y_min, int y_max, cv::Size size) {
  const int x_end = x_max == -1 ? size.width : x_max;
  const int y_end = y_max == -1 ? size.height : y_max;
  if (x_min < 0 || y_min < 0 || x_end > size.width || y_end > size.height || x_min >= x_end || y_min >= y_end)
    return std::nullopt;
  return cv::Rect(x_min, y_min, x_end - x_min, y_end - y_min);
}

// The same, throwing std::invalid_argument that names `what` and the bounds when it does not fit.
inline cv::Rect ResolveCrop(int x_min, int x_max, int y_min, int y_max, cv::Size size, const std::string& what) {
  if (auto crop = FitCrop(x_min, x_max, y_min, y_max, size)) return *crop;
  const auto edge = [](int max, int image) { return std::to_string(max == -1 ? image : max); };
  throw std::invalid_argument(what + " crop x [" + std::to_string(x_min) + ", " + edge(x_max, size.width) + ") y [" +
                              std::to_string(y_min) + ", " + edge(y_max, size.height) + ") does not fit the " +
                              std::to_string(size.width) + "x" + std::to_string(size.height) + " image");
}

}  // namespace rslam
