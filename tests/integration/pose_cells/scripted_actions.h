#pragma once
// The pose-cell actions of a scripted drive (scripted_loop.h), computed with the libraries, and
// the map an uninterrupted experience map builds from them: the oracle of the experience-map
// and restart tests.

#include <cstdint>
#include <utility>
#include <vector>

#include "rslam/msg/all_messages.h"
#include "services/experience_map/experience_map.h"
#include "services/pose_cells/pose_cell_network.h"
#include "tests/integration/pose_cells/scripted_loop.h"

namespace rslam::testing {

inline msg::ActionKind MessageKind(pose_cells::Action::Kind k) {
  switch (k) {
    case pose_cells::Action::Kind::kCreate: return msg::ActionKind::ACTION_CREATE;
    case pose_cells::Action::Kind::kLink: return msg::ActionKind::ACTION_LINK;
    case pose_cells::Action::Kind::kSet: return msg::ActionKind::ACTION_SET;
    case pose_cells::Action::Kind::kNone: break;
  }
  return msg::ActionKind::ACTION_NONE;
}

inline experience_map::ExperienceAction::Kind MapKind(msg::ActionKind k) {
  switch (k) {
    case msg::ActionKind::ACTION_CREATE: return experience_map::ExperienceAction::Kind::kCreate;
    case msg::ActionKind::ACTION_LINK: return experience_map::ExperienceAction::Kind::kLink;
    case msg::ActionKind::ACTION_SET: return experience_map::ExperienceAction::Kind::kSet;
    case msg::ActionKind::ACTION_NONE: break;
  }
  return experience_map::ExperienceAction::Kind::kNone;
}

// One action per frame, action_seq = frame number, as rslam-pose-cells publishes them.
inline std::vector<msg::PoseCellAction> ScriptedActions(const std::vector<ScriptedFrame>& frames,
                                                        const pose_cells::PoseCellConfig& config = {}) {
  pose_cells::PoseCellNetwork network(config);
  std::vector<msg::PoseCellAction> out;
  for (const ScriptedFrame& f : frames) {
    const pose_cells::Action a = network.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps, f.velocity.dt_s,
                                                      MatchOf(f));
    msg::PoseCellAction m;
    m.header = f.velocity.header;
    m.action_seq = out.size();
    m.kind = MessageKind(a.kind);
    m.experience_id = a.experience_id;
    m.from_experience_id = a.from_experience_id;
    m.template_id = a.template_id;
    m.pc_x = static_cast<float>(a.pc_x);
    m.pc_y = static_cast<float>(a.pc_y);
    m.pc_th = static_cast<float>(a.pc_th);
    m.vtrans_mps = f.velocity.vtrans_mps;
    m.vrot_radps = f.velocity.vrot_radps;
    m.dt_s = f.velocity.dt_s;
    out.push_back(m);
  }
  return out;
}

struct ReferenceMap {
  size_t experiences = 0;
  std::vector<std::pair<uint32_t, uint32_t>> links;  // in creation order
  size_t loop_closures = 0;
  std::vector<std::pair<double, double>> positions;  // per experience
};

// What an experience map that applied every action once, in order, holds.
inline ReferenceMap ApplyAll(const std::vector<msg::PoseCellAction>& actions,
                             const experience_map::ExperienceMapConfig& config = {}) {
  experience_map::ExperienceMap map(config);
  for (const msg::PoseCellAction& m : actions) {
    map.Integrate(m.vtrans_mps, m.vrot_radps, m.dt_s);
    experience_map::ExperienceAction a;
    a.kind = MapKind(m.kind);
    a.experience_id = m.experience_id;
    a.from_experience_id = m.from_experience_id;
    a.template_id = m.template_id;
    a.pc_x = m.pc_x;
    a.pc_y = m.pc_y;
    a.pc_th = m.pc_th;
    a.sequence = m.action_seq;
    map.Apply(a);
  }
  ReferenceMap r;
  r.experiences = map.experiences().size();
  for (const auto& l : map.links()) {
    r.links.emplace_back(l.from_id, l.to_id);
    r.loop_closures += l.closes_loop;
  }
  for (const auto& e : map.experiences()) r.positions.emplace_back(e.x_m, e.y_m);
  return r;
}

}  // namespace rslam::testing
