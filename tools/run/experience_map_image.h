#pragma once
// A picture of the experience map (as paper 000 fig. 10): experiences as dots, links as lines
// (loop-closure links red), the first experience green, the current one orange, auto-scaled with
// equal x/y scale and metre axes.

#include <opencv2/core.hpp>

#include <cstdint>
#include <set>
#include <utility>

#include "services/experience_map/experience_map.h"

namespace rslam::run {

cv::Mat DrawExperienceMap(const experience_map::ExperienceMap& map,
                          const std::set<std::pair<uint32_t, uint32_t>>& loop_closure_links,
                          cv::Size size = {900, 900});

}  // namespace rslam::run
