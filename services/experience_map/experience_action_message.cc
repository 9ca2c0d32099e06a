#include "services/experience_map/experience_action_message.h"

#include <stdexcept>
#include <vector>

#include "common/math/angle.h"

namespace rslam::experience_map {
namespace {

ExperienceAction::Kind ToKind(msg::ActionKind kind) {
  switch (kind) {
    case msg::ActionKind::ACTION_CREATE: return ExperienceAction::Kind::kCreate;
    case msg::ActionKind::ACTION_LINK: return ExperienceAction::Kind::kLink;
    case msg::ActionKind::ACTION_SET: return ExperienceAction::Kind::kSet;
    case msg::ActionKind::ACTION_NONE: break;
  }
  return ExperienceAction::Kind::kNone;
}

}  // namespace

ExperienceAction FromActionMessage(const msg::PoseCellAction& m) {
  ExperienceAction a;
  a.kind = ToKind(m.kind);
  a.experience_id = m.experience_id;
  a.from_experience_id = m.from_experience_id;
  a.template_id = m.template_id;
  a.relative_angle_rad = m.relative_angle_rad;
  a.offset_x_m = m.offset_x_m;
  a.offset_y_m = m.offset_y_m;
  a.pc_x = m.pc_x;
  a.pc_y = m.pc_y;
  a.pc_th = m.pc_th;
  a.sequence = m.action_seq;
  return a;
}

AppliedAction ApplyActionMessage(ExperienceMap& map, const msg::PoseCellAction& m) {
  AppliedAction applied;
  map.Integrate(m.vtrans_mps, m.vrot_radps, m.dt_s);
  if (m.wall_seen) {
    const bool had_axes = map.manhattan_axes().has_value();
    const uint64_t recaptures_before = map.heading_recaptures();
    const double heading_before = map.RobotPose().theta;
    map.HoldHeading(m.wall_direction_rad);
    applied.axes_fixed = !had_axes && map.manhattan_axes().has_value();
    if (map.heading_recaptures() != recaptures_before)
      applied.heading_recaptured_rad = WrapAngle(heading_before - map.RobotPose().theta);
  }
  try {
    map.Apply(FromActionMessage(m));
    applied.recognition_refused = map.last_refusal();
  } catch (const std::invalid_argument& e) {
    applied.ids_refused = e.what();
    map.Apply(ExperienceAction{});
  }
  if (m.boundary_measured && map.config().exp_scan_links) {
    std::vector<Eigen::Vector2f> points;
    points.reserve(m.boundary.size());
    for (const msg::FloorPoint& p : m.boundary) points.emplace_back(p.x_m, p.y_m);
    map.ObserveBoundary(points);
  }
  return applied;
}

void FillMapMessage(const ExperienceMap& map, msg::ExperienceMap& out) {
  out.current_experience_id = map.has_current() ? map.current_id() : kNoExperience;
  out.experiences.clear();
  out.experiences.reserve(map.experiences().size());
  for (const Experience& e : map.experiences()) {
    msg::Experience x{};
    x.id = e.id;
    x.x_m = e.x_m;
    x.y_m = e.y_m;
    x.theta_rad = e.th_rad;
    x.template_id = e.template_id;
    x.pc_x = static_cast<float>(e.pc_x);
    x.pc_y = static_cast<float>(e.pc_y);
    x.pc_th = static_cast<float>(e.pc_th);
    out.experiences.push_back(x);
  }
  out.links.clear();
  out.links.reserve(map.links().size());
  for (const Link& l : map.links()) {
    msg::ExperienceLink x{};
    x.from_id = l.from_id;
    x.to_id = l.to_id;
    x.distance_m = l.d_m;
    x.heading_rad = l.heading_rad;
    x.facing_rad = l.facing_rad;
    x.travel_time_s = l.travel_time_s;
    x.closes_loop = l.closes_loop;
    out.links.push_back(x);
  }
}

}  // namespace rslam::experience_map
