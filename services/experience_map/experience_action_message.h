#pragma once
// What the experience map applies for a pose_cells/action message; used by the service and by
// `rslam run`, so the two never drift.

#include "rslam/msg/all_messages.h"
#include "services/experience_map/experience_action.h"

namespace rslam::experience_map {

ExperienceAction FromActionMessage(const msg::PoseCellAction& message);

}  // namespace rslam::experience_map
