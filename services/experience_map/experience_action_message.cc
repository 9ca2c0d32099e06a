#include "services/experience_map/experience_action_message.h"

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
  a.pc_x = m.pc_x;
  a.pc_y = m.pc_y;
  a.pc_th = m.pc_th;
  a.sequence = m.action_seq;
  return a;
}

}  // namespace rslam::experience_map
