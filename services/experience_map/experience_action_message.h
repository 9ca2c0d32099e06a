#pragma once
// What the experience map applies for a pose_cells/action message, and the map in the
// experience_map/map message's form; used by the service, `rslam run` and the tests that compare
// the two, so they never drift.

#include "rslam/msg/all_messages.h"
#include "services/experience_map/experience_action.h"
#include "services/experience_map/experience_map.h"

namespace rslam::experience_map {

ExperienceAction FromActionMessage(const msg::PoseCellAction& message);

// Fills out's experiences, links and current_experience_id (kNoExperience when there is none);
// pose-cell coordinates become float as in the message. The header and versions are the caller's.
void FillMapMessage(const ExperienceMap& map, msg::ExperienceMap& out);

}  // namespace rslam::experience_map
