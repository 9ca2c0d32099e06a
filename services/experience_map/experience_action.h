#pragma once
// An action for the experience map, with explicit ids. Same fields and meaning as
// rslam::pose_cells::Action (see services/pose_cells/pose_cell_action.h); declared here so this
// library does not depend on the pose cells.

#include <cstdint>
#include <limits>

namespace rslam::experience_map {

inline constexpr uint32_t kNoExperience = std::numeric_limits<uint32_t>::max();

struct ExperienceAction {
  enum class Kind { kNone, kCreate, kLink, kSet };
  Kind kind = Kind::kNone;
  uint32_t experience_id = kNoExperience;       // created, linked-to or set experience
  uint32_t from_experience_id = kNoExperience;  // current experience before the action
  uint32_t template_id = 0;
  double relative_angle_rad = 0.0;  // view orientation offset, added to the facing on link/set
  // link/set: where the robot stands in the experience's frame (x forward, y left), as measured
  // by registering the two views' floor boundaries; zero: on it (OpenRatSLAM).
  double offset_x_m = 0.0, offset_y_m = 0.0;
  double pc_x = 0.0, pc_y = 0.0, pc_th = 0.0;  // pose-cell position of experience_id
  uint64_t sequence = 0;
};

}  // namespace rslam::experience_map
