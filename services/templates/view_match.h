#pragma once
// The template learner's match for one camera frame: what rslam-templates publishes
// (msg::ViewTemplate) and what the pose cells take with each frame's odometry.

#include <cmath>
#include <cstdint>

namespace rslam::templates {

struct ViewMatch {
  uint32_t template_id = 0;         // the matched template, or the new one (dense from 0)
  bool is_new = false;              // true when the view was learnt as a new template
  double relative_angle_rad = 0.0;  // the view's orientation offset gamma (001 eq. 4); 0 for a new template
  double difference = 0.0;          // to the matched template (or the best one, when new); 0 = identical
};

// `difference` sent when there was no template to compare with.
inline constexpr double kNoTemplateDifference = 1e9;

// The match as rslam-templates publishes it, and `rslam run` hands it on: messages with
// non-finite numbers are refused downstream, so an empty library's infinite difference is sent
// as kNoTemplateDifference and a non-finite angle as 0.
inline ViewMatch AsPublished(ViewMatch m) {
  if (!std::isfinite(m.relative_angle_rad)) m.relative_angle_rad = 0.0;
  if (!std::isfinite(m.difference)) m.difference = kNoTemplateDifference;
  return m;
}

}  // namespace rslam::templates
