#include "services/experience_map/experience_map_node.h"

#include "services/experience_map/experience_action_message.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "common/node/floor_boundary_check.h"
#include "common/persistence/state_file.h"
#include "services/experience_map/experience_map.h"
#include "services/experience_map/proto/experience_map_node_state.pb.h"

namespace rslam::experience_map {

namespace {

// State files and user map files are the same format.
constexpr const char* kStateKind = "rslam.experience_map.NodeState";
constexpr uint32_t kStateVersion = 1;

using Clock = std::chrono::steady_clock;

Clock::duration Seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

class ExperienceMapNode::Mapper {
 public:
  Mapper(ServiceContext& context, const Config& config)
      : context_(context), config_(config), map_(config.map), last_action_time_(Clock::now()), last_save_(Clock::now()) {
    LoadState();
    pose_pub_ = context_.Advertise(bus::topics::kExperienceMapPose);
    map_pub_ = context_.Advertise(bus::topics::kExperienceMapMap);
    idle_thread_ = std::thread([this] { IdleLoop(); });
  }

  ~Mapper() { StopIdleThread(); }

  // Stops processing, publishes the map if the last snapshot is behind it (so its subscribers end
  // with the final map), then saves the state (and the user's map file).
  void Stop() {
    bool published = false;
    {
      std::lock_guard lock(mutex_);
      stopped_ = true;
      try {
        if (SnapshotBehind()) {
          PublishMap();
          published = true;
        }
      } catch (const std::exception& e) {
        spdlog::error("could not publish the final map: {}", e.what());
      }
    }
    StopIdleThread();
    if (published && !map_pub_->WaitForAcknowledgments(std::chrono::seconds(1)))
      spdlog::warn("the final map was published but not every subscriber acknowledged it within 1 s");
    SaveState(/*force=*/false);
    if (!config_.save_map.empty()) {
      try {
        WriteStateFile(config_.save_map, kStateKind, kStateVersion, Snapshot());
        spdlog::info("saved the map to {}", config_.save_map);
      } catch (const std::exception& e) {
        spdlog::error("could not save the map to {}: {}", config_.save_map, e.what());
      }
    }
  }

  void Tick() {
    const auto now = Clock::now();
    {
      // The idle thread publishes catch-up snapshots; this is the safety net if it cannot.
      std::lock_guard lock(mutex_);
      if (!stopped_ && SnapshotBehind() && now - last_action_time_ >= Seconds(config_.idle_publish_s)) PublishMap();
    }
    if (now - last_save_ < Seconds(context_.runtime().state_save_period_s)) return;
    last_save_ = now;
    SaveState(false);
  }

  void OnAction(const msg::PoseCellAction& a) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    if (has_last_ && a.action_seq <= last_applied_) return;  // already applied (history replay)
    if (pending_.count(a.action_seq)) return;                  // duplicate of a waiting one
    std::optional<msg::PoseCellAction> entry;
    if (const std::string problem = ActionProblem(a); !problem.empty()) {
      // Keeps its place in the sequence (it arrived), but nothing of it is applied.
      context_.Reject("action", "action " + std::to_string(a.action_seq) + ": " + problem);
    } else {
      entry = a;
    }
    pending_.emplace(a.action_seq, std::move(entry));
    last_action_time_ = Clock::now();
    Drain(/*give_up_gap=*/false);
  }

 private:
  std::string ActionProblem(const msg::PoseCellAction& a) const {
    if (!std::isfinite(a.vtrans_mps) || !std::isfinite(a.vrot_radps) || !std::isfinite(a.dt_s))
      return "odometry has a non-finite number";
    if (a.dt_s < 0 || a.dt_s > config_.max_dt_s) return "dt " + std::to_string(a.dt_s) + " s is outside [0, max_dt_s]";
    if (!std::isfinite(a.pc_x) || !std::isfinite(a.pc_y) || !std::isfinite(a.pc_th))
      return "pose-cell position is not finite";
    if (!std::isfinite(a.relative_angle_rad)) return "relative angle is not finite";
    if (!std::isfinite(a.offset_x_m) || !std::isfinite(a.offset_y_m)) return "view offset is not finite";
    if (a.wall_seen && !std::isfinite(a.wall_direction_rad)) return "wall direction is not finite";
    return FloorBoundaryProblem(a.boundary_measured, a.boundary);
  }

  // Applies the waiting actions that are next in sequence. A gap is given up when it is too old
  // or too many actions wait behind it (give_up_gap forces it).
  void Drain(bool give_up_gap) {
    while (!pending_.empty()) {
      auto first = pending_.begin();
      const uint64_t expected = has_last_ ? last_applied_ + 1 : 0;
      if (first->first != expected) {
        if (!gap_since_) gap_since_ = Clock::now();
        const bool too_many = pending_.size() >= static_cast<size_t>(config_.gap_window_actions);
        const bool too_old = Clock::now() - *gap_since_ >= Seconds(config_.gap_timeout_s);
        if (!(give_up_gap || too_many || too_old)) return;
        context_.Reject("action_gap", "actions " + std::to_string(expected) + ".." + std::to_string(first->first - 1) +
                                          " never arrived; continuing after them");
        give_up_gap = false;
      }
      gap_since_.reset();
      std::optional<msg::PoseCellAction> action = std::move(first->second);
      const uint64_t seq = first->first;
      pending_.erase(first);
      if (action) Apply(*action);
      has_last_ = true;
      last_applied_ = seq;
      dirty_ = true;
    }
    gap_since_.reset();
  }

  // ------------------------------------------------------------------------------------------
  // Applying (mutex held)

  void Apply(const msg::PoseCellAction& m) {
    const uint32_t experiences_before = static_cast<uint32_t>(map_.experiences().size());
    const size_t links_before = map_.links().size();
    const AppliedAction applied = ApplyActionMessage(map_, m);  // validated on arrival
    if (applied.axes_fixed)
      spdlog::info("frame {}: the walls' axes are at {:.3f} rad (mod pi/2) in the map frame; holding the heading to them",
                   m.header.frame_seq, *map_.manhattan_axes());
    if (applied.heading_recaptured_rad)
      spdlog::info("frame {}: the walls agree the heading drifted {:.3f} rad past the hold's gate: taken out",
                   m.header.frame_seq, *applied.heading_recaptured_rad);
    if (applied.recognition_refused)
      spdlog::info("frame {}: recognition of experience {} refused: {}", m.header.frame_seq, m.experience_id,
                   ToString(*applied.recognition_refused));
    if (!applied.ids_refused.empty())
      context_.Reject("action_ids",
                      "action " + std::to_string(m.action_seq) + " (" + msg::ToString(m.kind) + "): " + applied.ids_refused);
    const bool structure_changed = map_.experiences().size() != experiences_before || map_.links().size() != links_before;
    if (structure_changed || m.kind == msg::ActionKind::ACTION_LINK || m.kind == msg::ActionKind::ACTION_SET ||
        map_.last_correction() > config_.map.exp_relax_tolerance) {
      ++map_version_;
    }
    last_header_ = m.header;
    context_.SetLastFrame(m.header.frame_seq, m.header.stamp_ns);
    PublishPose(m);
    ++actions_since_snapshot_;
    if (map_version_ != snapshot_version_ && actions_since_snapshot_ >= config_.map_publish_period_frames) PublishMap();
  }

  void PublishPose(const msg::PoseCellAction& m) {
    msg::ExperiencePose pose;
    pose.header = m.header;
    const Pose2D robot = map_.RobotPose();
    pose.x_m = robot.x;
    pose.y_m = robot.y;
    pose.theta_rad = robot.theta;
    if (map_.has_current()) {
      const Experience& e = map_.experiences()[map_.current_id()];
      pose.current_experience_id = e.id;
      pose.experience_x_m = e.x_m;
      pose.experience_y_m = e.y_m;
      pose.experience_theta_rad = e.th_rad;
    } else {
      pose.current_experience_id = kNoExperience;
    }
    pose.experience_count = static_cast<uint32_t>(map_.experiences().size());
    pose.link_count = static_cast<uint32_t>(map_.links().size());
    pose.map_version = map_version_;
    pose.action_seq = m.action_seq;
    pose_pub_->Publish(pose);
  }

  // ------------------------------------------------------------------------------------------
  // Snapshots (mutex held)

  bool SnapshotBehind() const {
    const bool has_map = has_last_ || !map_.experiences().empty();
    if (!has_map) return false;
    return !snapshot_published_ || snapshot_seq_ != last_applied_ || snapshot_version_ != map_version_;
  }

  void PublishMap() {
    msg::ExperienceMap out;
    out.header = last_header_;
    if (out.header.robot_id.empty()) out.header.robot_id = context_.robot_id();
    out.map_version = map_version_;
    out.action_seq = has_last_ ? last_applied_ : 0;
    FillMapMessage(map_, out);
    map_pub_->Publish(out);
    snapshot_published_ = true;
    snapshot_seq_ = out.action_seq;
    snapshot_version_ = map_version_;
    actions_since_snapshot_ = 0;
  }

  void IdleLoop() {
    const auto period = std::min<Clock::duration>(Seconds(config_.idle_publish_s / 4), std::chrono::milliseconds(50));
    std::unique_lock lock(mutex_);
    while (!stop_idle_) {
      idle_wake_.wait_for(lock, period);
      if (stop_idle_ || stopped_) break;
      const auto now = Clock::now();
      try {
        if (gap_since_ && now - *gap_since_ >= Seconds(config_.gap_timeout_s)) Drain(/*give_up_gap=*/true);
        if (SnapshotBehind() && now - last_action_time_ >= Seconds(config_.idle_publish_s)) PublishMap();
      } catch (const std::exception& e) {
        spdlog::error("idle snapshot: {}", e.what());
      }
    }
  }

  void StopIdleThread() {
    {
      std::lock_guard lock(mutex_);
      stop_idle_ = true;
    }
    idle_wake_.notify_all();
    if (idle_thread_.joinable()) idle_thread_.join();
  }

  // ------------------------------------------------------------------------------------------
  // State and map files

  void LoadState() {
    const std::string state_path = context_.StateFilePath();
    std::string path;
    if (!config_.load_map.empty()) {
      path = config_.load_map;  // the user's map replaces any saved state
    } else if (!state_path.empty() && !context_.runtime().fresh && std::filesystem::exists(state_path)) {
      path = state_path;
    }
    if (!path.empty()) {
      proto::NodeState state;
      ReadStateFile(path, kStateKind, kStateVersion, state);  // throws StateFileError when corrupt
      map_.Load(state.map());                                 // throws when inconsistent
      has_last_ = state.has_last_action();
      last_applied_ = state.last_action_seq();
      map_version_ = state.map_version();
      last_header_.robot_id = context_.robot_id();
      last_header_.frame_seq = state.last_frame_seq();
      last_header_.stamp_ns = state.last_stamp_ns();
      spdlog::info("loaded {}: {} experiences, {} links, last action {}", path, map_.experiences().size(),
                   map_.links().size(), has_last_ ? std::to_string(last_applied_) : std::string("none"));
    }
    if (!config_.merge_map.empty()) {
      proto::NodeState other_state;
      ReadStateFile(config_.merge_map, kStateKind, kStateVersion, other_state);
      if (map_.experiences().empty()) {
        map_.Load(other_state.map());
      } else {
        ExperienceMap other(config_.map);
        other.Load(other_state.map());
        map_.MergeFrom(other, {});
      }
      ++map_version_;
      spdlog::info("merged {}: the map now has {} experiences", config_.merge_map, map_.experiences().size());
    }
  }

  proto::NodeState Snapshot() {
    std::lock_guard lock(mutex_);
    return SnapshotLocked();
  }

  proto::NodeState SnapshotLocked() const {
    proto::NodeState state;
    *state.mutable_map() = map_.Save();
    state.set_has_last_action(has_last_);
    state.set_last_action_seq(last_applied_);
    state.set_map_version(map_version_);
    state.set_last_frame_seq(last_header_.frame_seq);
    state.set_last_stamp_ns(last_header_.stamp_ns);
    return state;
  }

  void SaveState(bool force) {
    const std::string path = context_.StateFilePath();
    if (path.empty()) return;
    proto::NodeState state;
    {
      std::lock_guard lock(mutex_);
      if (!dirty_ && !force) return;
      state = SnapshotLocked();
      dirty_ = false;
    }
    if (!WriteStateFileOrLog(path, kStateKind, kStateVersion, state)) {
      std::lock_guard lock(mutex_);
      dirty_ = true;  // try again at the next save
    }
  }

  ServiceContext& context_;
  const Config config_;
  std::shared_ptr<bus::Publisher<msg::ExperiencePose>> pose_pub_;
  std::shared_ptr<bus::Publisher<msg::ExperienceMap>> map_pub_;

  std::mutex mutex_;
  bool stopped_ = false;
  ExperienceMap map_;
  bool has_last_ = false;
  uint64_t last_applied_ = 0;
  std::map<uint64_t, std::optional<msg::PoseCellAction>> pending_;  // nullopt: arrived, refused
  std::optional<Clock::time_point> gap_since_;
  uint64_t map_version_ = 0;
  msg::Header last_header_;
  bool snapshot_published_ = false;
  uint64_t snapshot_seq_ = 0;
  uint64_t snapshot_version_ = 0;
  int actions_since_snapshot_ = 0;
  Clock::time_point last_action_time_;
  bool dirty_ = true;  // a fresh start saves too, so a restart sees the file
  Clock::time_point last_save_;

  std::condition_variable idle_wake_;
  bool stop_idle_ = false;
  std::thread idle_thread_;
};

ExperienceMapNode::ExperienceMapNode(ServiceContext& context, const Config& config)
    : mapper_(std::make_unique<Mapper>(context, config)) {
  Mapper* m = mapper_.get();
  action_sub_ = context.Subscribe<msg::PoseCellAction>(bus::topics::kPoseCellsAction,
                                                       [m](const msg::PoseCellAction& a) { m->OnAction(a); });
}

ExperienceMapNode::~ExperienceMapNode() {
  action_sub_.reset();  // no callback runs after this
  mapper_->Stop();
}

void ExperienceMapNode::Tick() { mapper_->Tick(); }

}  // namespace rslam::experience_map
