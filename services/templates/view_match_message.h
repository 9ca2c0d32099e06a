#pragma once
// A view match as it travels on templates/view (msg::ViewTemplate), both ways: built here by
// rslam-templates, read here by rslam-pose-cells and by the tests that stand in for either.

#include <cstdint>

#include "rslam/msg/templates.h"
#include "services/templates/view_match.h"

namespace rslam::templates {

// The message for a frame's match (AsPublished: no non-finite numbers go out).
inline msg::ViewTemplate ToViewMessage(const msg::Header& header, const ViewMatch& match, uint32_t template_count) {
  const ViewMatch sent = AsPublished(match);
  msg::ViewTemplate out;
  out.header = header;
  out.template_id = sent.template_id;
  out.is_new = sent.is_new;
  out.relative_angle_rad = sent.relative_angle_rad;
  out.difference = sent.difference;
  out.template_count = template_count;
  return out;
}

inline ViewMatch FromViewMessage(const msg::ViewTemplate& m) {
  return {m.template_id, m.is_new, m.relative_angle_rad, m.difference};
}

}  // namespace rslam::templates
