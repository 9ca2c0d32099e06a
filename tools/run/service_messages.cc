#include "tools/run/service_messages.h"

#include <cmath>

namespace rslam::run {

namespace {

msg::ActionKind ToMessageKind(pose_cells::Action::Kind kind) {
  switch (kind) {
    case pose_cells::Action::Kind::kCreate: return msg::ActionKind::ACTION_CREATE;
    case pose_cells::Action::Kind::kLink: return msg::ActionKind::ACTION_LINK;
    case pose_cells::Action::Kind::kSet: return msg::ActionKind::ACTION_SET;
    case pose_cells::Action::Kind::kNone: break;
  }
  return msg::ActionKind::ACTION_NONE;
}

experience_map::ExperienceAction::Kind ToExperienceKind(msg::ActionKind kind) {
  switch (kind) {
    case msg::ActionKind::ACTION_CREATE: return experience_map::ExperienceAction::Kind::kCreate;
    case msg::ActionKind::ACTION_LINK: return experience_map::ExperienceAction::Kind::kLink;
    case msg::ActionKind::ACTION_SET: return experience_map::ExperienceAction::Kind::kSet;
    case msg::ActionKind::ACTION_NONE: break;
  }
  return experience_map::ExperienceAction::Kind::kNone;
}

}  // namespace

msg::PoseCellAction PoseCellActionMessage(const pose_cells::Action& action, uint64_t action_seq, double vtrans_mps,
                                          double vrot_radps, double dt_s) {
  msg::PoseCellAction out{};
  out.action_seq = action_seq;
  out.kind = ToMessageKind(action.kind);
  out.experience_id = action.experience_id;
  out.from_experience_id = action.from_experience_id;
  out.template_id = action.template_id;
  out.pc_x = static_cast<float>(action.pc_x);
  out.pc_y = static_cast<float>(action.pc_y);
  out.pc_th = static_cast<float>(action.pc_th);
  out.vtrans_mps = vtrans_mps;
  out.vrot_radps = vrot_radps;
  out.dt_s = dt_s;
  out.relative_angle_rad = action.relative_angle_rad;
  return out;
}

experience_map::ExperienceAction ExperienceActionFromMessage(const msg::PoseCellAction& m) {
  experience_map::ExperienceAction a;
  a.kind = ToExperienceKind(m.kind);
  a.experience_id = m.experience_id;
  a.from_experience_id = m.from_experience_id;
  a.template_id = m.template_id;
  a.relative_angle_rad = m.relative_angle_rad;
  a.pc_x = m.pc_x;
  a.pc_y = m.pc_y;
  a.pc_th = m.pc_th;
  a.sequence = m.action_seq;
  return a;
}

double PublishedRelativeAngle(double relative_angle_rad) {
  return std::isfinite(relative_angle_rad) ? relative_angle_rad : 0.0;
}

}  // namespace rslam::run
