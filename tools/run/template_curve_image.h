#pragma once
// The template-learning curve (paper 000 fig. 9a): templates stored against frames processed.
// A curve that flattens means the robot is revisiting known places.

#include <opencv2/core.hpp>

#include <vector>

#include "tools/run/run_statistics.h"

namespace rslam::run {

cv::Mat DrawTemplateCurve(const std::vector<TemplateCurvePoint>& curve, cv::Size size = {900, 500});

}  // namespace rslam::run
