#pragma once
// What the pose cells tell the experience map after each camera frame, with explicit ids.
//
// The pose-cell side owns the bookkeeping that decides whether the robot is at a new place or a
// known one (OpenRatSLAM's PosecellNetwork::get_action), so the experience map only applies
// actions. Ids are dense: experience k is created by the k-th kCreate. Every emitted action
// (kind != kNone) carries the next `sequence` number (0, 1, 2, ...), so a consumer that sees a
// gap knows it missed actions and can ask for a resynchronisation instead of drifting silently.
//
//   kCreate: a new experience `experience_id` (== number of experiences before it) was made at
//            the current pose-cell position; it is linked from `from_experience_id` (the
//            previous current experience), or from nothing for the very first experience
//            (from_experience_id == kNoExperience). It becomes the current experience.
//   kLink:   the robot recognised experience `experience_id` (a loop closure) while current was
//            `from_experience_id`, and no link between the two existed: link from -> id, then
//            `experience_id` becomes current.
//   kSet:    as kLink, but the two experiences were already linked (either direction): no new
//            link, `experience_id` becomes current.
//   kNone:   nothing changed; `sequence` is not consumed.
//
// relative_angle_rad is the orientation offset of the view that drove the decision (001 eqs.
// 3-4); the experience map adds it to the facing of the experience it moves to.

#include <cstdint>
#include <limits>

namespace rslam::pose_cells {

inline constexpr uint32_t kNoExperience = std::numeric_limits<uint32_t>::max();

struct Action {
  enum class Kind { kNone, kCreate, kLink, kSet };
  Kind kind = Kind::kNone;
  uint32_t experience_id = kNoExperience;       // created, linked-to or set experience
  uint32_t from_experience_id = kNoExperience;  // current experience before the action
  uint32_t template_id = 0;                     // view template of the frame
  double relative_angle_rad = 0.0;              // view orientation offset
  // kLink/kSet with exp_view_offset or exp_boundary_offset: where the robot stands in
  // experience_id's frame (x forward, y left, metres) as measured from the best recent view and
  // the odometry, or as the two floor boundaries register; zero when not measured.
  double offset_x_m = 0.0;
  double offset_y_m = 0.0;
  // Pose-cell position (cells) of experience_id.
  double pc_x = 0.0;
  double pc_y = 0.0;
  double pc_th = 0.0;
  uint64_t sequence = 0;  // meaningful only when kind != kNone
  // The pose cells recognised experience refused_link_to but its floor boundary did not match
  // the view's (exp_boundary_check): this kCreate was made instead of the link.
  uint32_t refused_link_to = kNoExperience;
};

}  // namespace rslam::pose_cells
