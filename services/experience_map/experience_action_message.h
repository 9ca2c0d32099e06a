#pragma once
// What the experience map applies for a pose_cells/action message, and the map in the
// experience_map/map message's form; used by the service, `rslam run`, `rslam eval map` and the
// tests that compare them, so they never drift.

#include <optional>
#include <string>

#include "rslam/msg/all_messages.h"
#include "services/experience_map/experience_action.h"
#include "services/experience_map/experience_map.h"

namespace rslam::experience_map {

ExperienceAction FromActionMessage(const msg::PoseCellAction& message);

// What ApplyActionMessage did beyond the map's own bookkeeping, for the service's log.
struct AppliedAction {
  bool axes_fixed = false;                       // this frame's wall direction fixed the building's axes
  std::optional<double> heading_recaptured_rad;  // the heading taken back from past the hold's gate by this much
  // The recognition a gate of exp_recognition_max_* refused, and why.
  std::optional<RecognitionRefusal> recognition_refused;
  std::string ids_refused;  // non-empty: why the action's ids did not fit (an empty action was applied instead)
};

// One validated pose_cells/action message as the service applies it: its odometry integrated, its
// wall direction held (exp_manhattan), then the action (one whose ids do not fit is replaced by an
// empty one, so the frame's correction budget is still spent), then its floor boundary kept
// (exp_scan_links).
AppliedAction ApplyActionMessage(ExperienceMap& map, const msg::PoseCellAction& message);

// Fills out's experiences, links and current_experience_id (kNoExperience when there is none);
// pose-cell coordinates become float as in the message. The header and versions are the caller's.
void FillMapMessage(const ExperienceMap& map, msg::ExperienceMap& out);

}  // namespace rslam::experience_map
