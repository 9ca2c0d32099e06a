#include "tools/eval/map_replay.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "services/experience_map/experience_action_message.h"
#include "services/experience_map/experience_map.h"
#include "services/occupancy/anchored_profile_map.h"
#include "services/occupancy/profile_message.h"
#include "services/pose_cells/pose_cell_action_message.h"
#include "services/pose_cells/pose_cell_network.h"

namespace rslam::eval {

namespace {

bool SameAction(const msg::PoseCellAction& a, const msg::PoseCellAction& b) {
  return a.kind == b.kind && a.experience_id == b.experience_id && a.from_experience_id == b.from_experience_id &&
         a.template_id == b.template_id && a.relative_angle_rad == b.relative_angle_rad &&
         a.offset_x_m == b.offset_x_m && a.offset_y_m == b.offset_y_m && a.pc_x == b.pc_x && a.pc_y == b.pc_y &&
         a.pc_th == b.pc_th && a.vtrans_mps == b.vtrans_mps && a.vrot_radps == b.vrot_radps && a.dt_s == b.dt_s &&
         a.wall_seen == b.wall_seen && (!a.wall_seen || a.wall_direction_rad == b.wall_direction_rad) &&
         a.boundary_measured == b.boundary_measured && a.boundary == b.boundary;
}

}  // namespace

MapReplayResult ReplayMap(const RecordedRun& run, const MapReplayConfig& config) {
  MapReplayResult result;
  demo::DemoObservations& seen = result.seen;
  pose_cells::PoseCellNetwork network(config.pose_cells.network);
  experience_map::ExperienceMap map(config.experience_map.map);
  occupancy::AnchoredProfileMap profiles(config.occupancy.grid, config.occupancy.sensor,
                                         config.occupancy.profile_alignment);
  pose_cells::FloorBoundary scratch;
  uint64_t next_action_seq = 0;
  std::optional<int64_t> last_stamp_ns;
  std::size_t replayed = 0;

  for (const RecordedFrame& frame : run.frames) {
    msg::Header header;
    header.robot_id = run.robot;
    header.frame_seq = frame.frame_seq;
    header.stamp_ns = frame.stamp_ns;
    if (frame.truth) seen.ground_truth.push_back({frame.frame_seq, frame.stamp_ns, frame.truth->x, frame.truth->y, frame.truth->theta});
    if (frame.velocity) {
      const msg::Velocity& v = *frame.velocity;
      seen.odometry.push_back({frame.frame_seq, frame.stamp_ns, v.vtrans_mps, v.vrot_radps, v.dt_s});
    }
    if (frame.view) seen.template_count = std::max(seen.template_count, frame.view->template_count);

    // The pose-cell service's frame (PoseCellsNode::ProcessFrame), or the recorded action.
    msg::PoseCellAction action;
    if (config.recorded_actions) {
      if (!frame.action) continue;
      action = *frame.action;
    } else {
      if (!frame.velocity && !frame.view) continue;
      const msg::Velocity* velocity = frame.velocity ? &*frame.velocity : nullptr;
      const pose_cells::FrameOdometry odometry =
          pose_cells::OdometryOf(velocity, frame.stamp_ns, last_stamp_ns, config.pose_cells.max_dt_s);
      try {
        action = pose_cells::StepFrame(network, header, velocity, odometry, frame.view ? &*frame.view : nullptr,
                                       next_action_seq, scratch)
                     .message;
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("frame " + std::to_string(frame.frame_seq) + ": " + e.what());
      }
      ++next_action_seq;
      last_stamp_ns = frame.stamp_ns;
      if (frame.action) {
        ++result.actions_compared;
        if (!SameAction(action, *frame.action)) ++result.actions_differing;
      }
    }
    ++replayed;

    // The experience-map service's (ExperienceMapNode::Apply; an action it would refuse whole is
    // skipped).
    if (action.dt_s > config.experience_map.max_dt_s) continue;
    const experience_map::AppliedAction applied = experience_map::ApplyActionMessage(map, action);
    if (applied.axes_fixed) result.axes_fixed = MapReplayResult::AxesFixed{frame.frame_seq, *map.manhattan_axes()};
    if (applied.heading_recaptured_rad)
      result.heading_recaptures.push_back({frame.frame_seq, *applied.heading_recaptured_rad});
    const Pose2D robot = map.RobotPose();
    seen.experience_poses.push_back({frame.frame_seq, frame.stamp_ns, robot.x, robot.y, robot.theta});
    uint32_t current = pose_cells::kNoExperience;
    Pose2D experience;
    if (map.has_current()) {
      const experience_map::Experience& e = map.experiences()[map.current_id()];
      current = e.id;
      experience = e.pose();
    }
    seen.experience_first_frame.emplace(current, frame.frame_seq);

    // The occupancy service's (OccupancyNode::ProcessFrame): the frame's profile anchored to the
    // experience current at it.
    if (frame.profile) {
      occupancy::AnchoredProfile anchored{current, Between(experience, robot), experience, {}, {}};
      anchored.profile = occupancy::ProfileFromMessage(*frame.profile);
      if (profiles.IsNewView(current, anchored.offset, config.occupancy.profile_min_spacing_m,
                             config.occupancy.profile_min_turn_rad)) {
        profiles.AddProfile(std::move(anchored));
        ++result.profiles_kept;
      }
    }
  }
  if (replayed == 0)
    throw std::invalid_argument(config.recorded_actions ? "the recording holds no pose_cells/action of the robot"
                                                        : "the recording holds no odometry/velocity or templates/view of the robot");

  msg::ExperienceMap final_map;
  final_map.header.robot_id = run.robot;
  experience_map::FillMapMessage(map, final_map);
  std::unordered_map<uint64_t, Pose2D> poses;
  for (const msg::Experience& e : final_map.experiences) poses[e.id] = {e.x_m, e.y_m, e.theta_rad};
  profiles.Rebuild([&poses](uint64_t id) -> std::optional<Pose2D> {
    if (auto it = poses.find(id); it != poses.end()) return it->second;
    return std::nullopt;
  });
  seen.grid = occupancy::GridToMessage(profiles.grid());
  seen.experience_count = static_cast<uint32_t>(final_map.experiences.size());
  seen.link_count = static_cast<uint32_t>(final_map.links.size());
  seen.map = std::move(final_map);
  result.scan_registrations = map.scan_registrations();
  result.scan_links = map.scan_links();
  return result;
}

std::vector<ScanLinkError> JudgeScanLinks(std::span<const experience_map::ScanLink> links,
                                          const std::map<uint32_t, Pose2D>& experience_truth) {
  std::vector<ScanLinkError> out;
  for (const experience_map::ScanLink& s : links) {
    const auto from = experience_truth.find(s.link.from_id), to = experience_truth.find(s.link.to_id);
    if (from == experience_truth.end() || to == experience_truth.end()) continue;
    const Pose2D truth = Between(from->second, to->second);
    const Pose2D measured = s.link.pose();
    out.push_back({s.link.from_id, s.link.to_id, std::hypot(measured.x - truth.x, measured.y - truth.y),
                   std::abs(WrapAngle(measured.theta - truth.theta))});
  }
  return out;
}

std::vector<RecaptureError> JudgeRecaptures(std::span<const MapReplayResult::Recapture> recaptures,
                                            const demo::DemoObservations& seen, const Pose2D& map_origin) {
  std::unordered_map<uint64_t, double> truth;
  for (const demo::FramePose& p : seen.ground_truth) truth[p.frame_seq] = p.theta;
  const auto error = [&](const demo::FramePose& map_pose) -> std::optional<double> {
    const auto t = truth.find(map_pose.frame_seq);
    if (t == truth.end()) return std::nullopt;
    return WrapAngle(map_origin.theta + map_pose.theta - t->second);
  };
  std::vector<RecaptureError> out;
  const std::vector<demo::FramePose>& poses = seen.experience_poses;
  for (const MapReplayResult::Recapture& r : recaptures) {
    const auto at = std::find_if(poses.begin(), poses.end(),
                                 [&r](const demo::FramePose& p) { return p.frame_seq == r.frame; });
    if (at == poses.end() || at == poses.begin()) continue;
    const std::optional<double> before = error(*(at - 1)), after = error(*at);
    if (before && after) out.push_back({r.frame, r.taken_rad, *before, *after});
  }
  return out;
}

}  // namespace rslam::eval
