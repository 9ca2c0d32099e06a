#include "services/pose_cells/pose_cell_action_message.h"

#include <algorithm>

#include "services/templates/view_match_message.h"

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

FrameOdometry OdometryOf(const msg::Velocity* velocity, int64_t stamp_ns, std::optional<int64_t> last_stamp_ns,
                         double max_dt_s) {
  if (velocity) return {velocity->vtrans_mps, velocity->vrot_radps, velocity->dt_s};
  if (!last_stamp_ns || stamp_ns <= *last_stamp_ns) return {};
  return {0.0, 0.0, std::min(max_dt_s, static_cast<double>(stamp_ns - *last_stamp_ns) * 1e-9)};
}

FrameStep StepFrame(PoseCellNetwork& network, const msg::Header& header, const msg::Velocity* velocity,
                    const FrameOdometry& odometry, const msg::ViewTemplate* view, uint64_t action_seq,
                    FloorBoundary& scratch) {
  const auto [vtrans_mps, vrot_radps, dt_s] = odometry;
  // The boundary matters only to the checks and the offsets: without them nothing is converted.
  const FloorBoundary* seen = nullptr;
  const PoseCellConfig& config = network.config();
  if ((config.exp_boundary_check || config.exp_boundary_offset || config.exp_submap_offset) && velocity &&
      velocity->boundary_measured) {
    scratch.clear();
    for (const msg::FloorPoint& p : velocity->boundary) scratch.emplace_back(p.x_m, p.y_m);
    seen = &scratch;
  }
  FrameStep step;
  step.action = view ? network.ProcessFrame(vtrans_mps, vrot_radps, dt_s, templates::FromViewMessage(*view), seen)
                     : network.ProcessFrameWithoutView(vtrans_mps, vrot_radps, dt_s, seen);
  step.message = ToActionMessage(step.action, action_seq, vtrans_mps, vrot_radps, dt_s);
  step.message.header = header;
  if (velocity) {  // for the experience map (exp_manhattan, exp_scan_links)
    step.message.wall_seen = velocity->wall_seen;
    step.message.wall_direction_rad = velocity->wall_seen ? velocity->wall_direction_rad : 0.0;
    step.message.boundary_measured = velocity->boundary_measured;
    step.message.boundary = velocity->boundary;
  }
  return step;
}

}  // namespace rslam::pose_cells
