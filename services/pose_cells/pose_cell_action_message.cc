#include "services/pose_cells/pose_cell_action_message.h"

namespace rslam::pose_cells {
namespace {

msg::ActionKind ToMessageKind(Action::Kind kind) {
  switch (kind) {
    case Action::Kind::kCreate: return msg::ActionKind::ACTION_CREATE;
    case Action::Kind::kLink: return msg::ActionKind::ACTION_LINK;
    case Action::Kind::kSet: return msg::ActionKind::ACTION_SET;
    case Action::Kind::kNone: break;
  }
  return msg::ActionKind::ACTION_NONE;
}

}  // namespace

msg::PoseCellAction ToActionMessage(const Action& action, uint64_t action_seq, double vtrans_mps, double vrot_radps,
                                    double dt_s) {
  msg::PoseCellAction out;
  out.action_seq = action_seq;
  out.kind = ToMessageKind(action.kind);
  out.experience_id = action.experience_id;
  out.from_experience_id = action.from_experience_id;
  out.template_id = action.template_id;
  out.relative_angle_rad = action.relative_angle_rad;
  out.offset_x_m = action.offset_x_m;
  out.offset_y_m = action.offset_y_m;
  out.pc_x = static_cast<float>(action.pc_x);
  out.pc_y = static_cast<float>(action.pc_y);
  out.pc_th = static_cast<float>(action.pc_th);
  out.vtrans_mps = vtrans_mps;
  out.vrot_radps = vrot_radps;
  out.dt_s = dt_s;
  return out;
}

}  // namespace rslam::pose_cells
