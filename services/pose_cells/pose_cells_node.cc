#include "services/pose_cells/pose_cells_node.h"

#include "services/pose_cells/pose_cell_action_message.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/node/floor_boundary_check.h"
#include "common/persistence/state_file.h"
#include "services/pose_cells/pose_cell_network.h"
#include "services/pose_cells/proto/pose_cells_node_state.pb.h"
#include "services/pose_cells/velocity_view_joiner.h"

namespace rslam::pose_cells {

namespace {

constexpr const char* kStateKind = "rslam.pose_cells.NodeState";
constexpr uint32_t kStateVersion = 1;

}  // namespace

class PoseCellsNode::Processor {
 public:
  Processor(ServiceContext& context, const Config& config)
      : context_(context),
        config_(config),
        network_(config.network),
        joiner_(static_cast<uint64_t>(config.join_window_frames),
                static_cast<int64_t>(config.join_timeout_s * 1e9)),
        last_save_(std::chrono::steady_clock::now()) {
    LoadState();
    action_pub_ = context_.Advertise(bus::topics::kPoseCellsAction);
  }

  void OnVelocity(const msg::Velocity& v) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    const uint64_t seq = v.header.frame_seq;
    if (const std::string problem = VelocityProblem(v); !problem.empty()) {
      context_.Reject("velocity", problem);
      joiner_.SkipVelocity(seq);
    } else if (!joiner_.AddVelocity(seq, v, NowNs())) {
      context_.Reject("late_velocity", "odometry for frame " + std::to_string(seq) + " came after the frame was processed");
    }
    ProcessReady();
  }

  void OnView(const msg::ViewTemplate& v) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    const uint64_t seq = v.header.frame_seq;
    if (const std::string problem = ViewProblem(v); !problem.empty()) {
      context_.Reject("view", problem);
      joiner_.SkipView(seq);
    } else if (!joiner_.AddView(seq, v, NowNs())) {
      context_.Reject("late_view", "view for frame " + std::to_string(seq) + " came after the frame was processed");
      // Its frame went on without it, but a template it learnt keeps its id: recorded unplaced, so
      // the next views' ids follow on (associated with a place at its next sighting).
      if (v.template_id >= network_.template_count() && v.template_id - network_.template_count() <= frames_without_view_)
        network_.SkipTemplates(v.template_id + 1);
    }
    ProcessReady();
  }

  void Resynchronise() {
    std::optional<msg::ExperienceMap> snapshot = AwaitMapSnapshot();
    std::lock_guard lock(mutex_);
    if (snapshot) AdoptSnapshot(*snapshot);
    if (restarted_) relocalise_frames_left_ = config_.restart_relocalise_frames;
    resynced_ = true;
    ProcessReady();
  }

  void Stop() {
    {
      std::lock_guard lock(mutex_);
      stopped_ = true;
      if (config_.network.exp_boundary_check || config_.network.exp_submap_check)
        spdlog::info("floor boundary checks: {} loop closures refused", refused_links_);
    }
    SaveState();
  }

  void Tick() {
    {
      // A frame whose partner stream died is released here when no other input comes.
      std::lock_guard lock(mutex_);
      if (!stopped_) ProcessReady();
    }
    const auto now = std::chrono::steady_clock::now();
    if (now - last_save_ < std::chrono::duration<double>(context_.runtime().state_save_period_s)) return;
    last_save_ = now;
    SaveState();
  }

 private:
  // ------------------------------------------------------------------------------------------
  // Input validation

  std::string VelocityProblem(const msg::Velocity& v) const {
    if (!std::isfinite(v.vtrans_mps) || !std::isfinite(v.vrot_radps) || !std::isfinite(v.dt_s))
      return "odometry has a non-finite number";
    if (v.dt_s < 0 || v.dt_s > config_.max_dt_s)
      return "dt " + std::to_string(v.dt_s) + " s is outside [0, max_dt_s=" + std::to_string(config_.max_dt_s) + "]";
    if (std::abs(v.vtrans_mps) > config_.max_vtrans_mps) return "|vtrans| " + std::to_string(v.vtrans_mps) + " m/s is beyond max_vtrans_mps";
    if (std::abs(v.vrot_radps) > config_.max_vrot_radps) return "|vrot| " + std::to_string(v.vrot_radps) + " rad/s is beyond max_vrot_radps";
    return FloorBoundaryProblem(v.boundary_measured, v.boundary);
  }

  static std::string ViewProblem(const msg::ViewTemplate& v) {
    if (!std::isfinite(v.relative_angle_rad)) return "view relative angle is not finite";
    if (!std::isfinite(v.difference) || v.difference < 0) return "view difference is not finite and >= 0";
    if (v.template_id >= v.template_count)
      return "template id " + std::to_string(v.template_id) + " is not below the template count " +
             std::to_string(v.template_count);
    return "";
  }

  // ------------------------------------------------------------------------------------------
  // Processing (mutex held)

  static int64_t NowNs() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

  void ProcessReady() {
    if (!resynced_) return;  // frames wait in the joiner until the ids are known to agree
    for (auto& frame : joiner_.TakeReady(NowNs())) ProcessFrame(frame);
    const uint64_t incomplete = joiner_.incomplete();
    for (; reported_incomplete_ < incomplete; ++reported_incomplete_) {
      context_.Reject("incomplete_frame", "a frame's odometry or view never came; processed with the side it had");
    }
  }

  using Joiner = VelocityViewJoiner<msg::Velocity, msg::ViewTemplate>;

  void ProcessFrame(const Joiner::Frame& frame) {
    const msg::Header& header = frame.velocity ? frame.velocity->header : frame.view->header;
    const msg::Velocity* velocity = frame.velocity ? &*frame.velocity : nullptr;
    const FrameOdometry odometry =
        OdometryOf(velocity, header.stamp_ns, has_last_frame_ ? std::optional(last_stamp_ns_) : std::nullopt,
                   config_.max_dt_s);
    const msg::ViewTemplate* view = frame.view ? &*frame.view : nullptr;
    if (view && view->template_id > network_.template_count()) {
      // The template learner learns at most one template per frame, so the templates this
      // network never saw fit in the frames it never saw or saw without their view (it was down,
      // or they were lost or late); more than that is a malformed id.
      const uint64_t missed = view->template_id - network_.template_count();
      const uint64_t unseen_frames =
          (has_last_frame_ ? (frame.frame_seq > last_frame_seq_ ? frame.frame_seq - last_frame_seq_ - 1 : 0)
                           : frame.frame_seq) +
          frames_without_view_;
      if (missed <= unseen_frames) {
        network_.SkipTemplates(view->template_id);
      } else {
        context_.Reject("view", "template id " + std::to_string(view->template_id) + " skips " + std::to_string(missed) +
                                    " templates past the next expected id " + std::to_string(network_.template_count()) +
                                    " in " + std::to_string(unseen_frames) + " unseen frames");
        view = nullptr;
      }
    }
    if (bridge_pending_) BridgeMissedFrames(frame.frame_seq, header.stamp_ns, odometry.dt_s);
    if (relocalise_frames_left_ > 0) Relocalise(frame.frame_seq, view);
    FrameStep step;
    try {
      step = StepFrame(network_, header, velocity, odometry, view, next_action_seq_, boundary_);
    } catch (const std::invalid_argument& e) {
      context_.Reject("frame", e.what());
      return;
    }
    ++next_action_seq_;
    frames_without_view_ = view ? 0 : frames_without_view_ + 1;
    if (step.action.refused_link_to != kNoExperience) {
      ++refused_links_;
      spdlog::debug("frame {}: link to experience {} refused by the floor boundaries ({} so far)", header.frame_seq,
                    step.action.refused_link_to, refused_links_);
    }
    if (velocity) mean_vtrans_mps_ += 0.1 * (odometry.vtrans_mps - mean_vtrans_mps_);
    has_last_frame_ = true;
    last_frame_seq_ = header.frame_seq;
    last_stamp_ns_ = header.stamp_ns;
    dirty_ = true;
    context_.SetLastFrame(header.frame_seq, header.stamp_ns);
    action_pub_->Publish(step.message);
  }

  // After a restart from the saved state: the robot kept moving through the frames this service
  // never saw. Their odometry is gone; the recent forward speed over the time they took is the
  // best guess (rotation is not extrapolated: turns are short and would mislead more).
  void BridgeMissedFrames(uint64_t frame_seq, int64_t stamp_ns, double frame_dt_s) {
    bridge_pending_ = false;
    if (!has_last_frame_ || frame_seq <= last_frame_seq_ + 1 || stamp_ns <= last_stamp_ns_) return;
    const double gap_s = static_cast<double>(stamp_ns - last_stamp_ns_) * 1e-9 - frame_dt_s;
    if (!(gap_s > 0)) return;
    network_.PathIntegrate(mean_vtrans_mps_, 0.0, std::min(gap_s, config_.max_dt_s));
    network_.UpdateBestPose();
    spdlog::info("bridged {} missed frames ({:.2f} s) at {:.2f} m/s", frame_seq - last_frame_seq_ - 1, gap_s,
                 mean_vtrans_mps_);
  }

  // After a restart: the frames this service never saw moved the robot; the first familiar view
  // says where it is now.
  void Relocalise(uint64_t frame_seq, const msg::ViewTemplate* view) {
    if (has_last_frame_ && frame_seq == last_frame_seq_ + 1) {
      relocalise_frames_left_ = 0;  // nothing was missed
      return;
    }
    --relocalise_frames_left_;
    if (view && network_.RelocaliseToView(view->template_id, view->relative_angle_rad)) {
      relocalise_frames_left_ = 0;
      spdlog::info("relocalised the pose cells by the view of template {} at frame {}", view->template_id, frame_seq);
    }
  }

  // ------------------------------------------------------------------------------------------
  // Resynchronisation

  std::optional<msg::ExperienceMap> AwaitMapSnapshot() {
    if (config_.resync_timeout_s <= 0) return std::nullopt;
    bus::Subscriber<msg::ExperienceMap> maps(context_.participant(), bus::topics::kExperienceMapMap);
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(config_.resync_timeout_s));
    const auto settle = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.resync_settle_s));
    std::optional<msg::ExperienceMap> latest;
    while (true) {
      const auto now = Clock::now();
      // Before the first snapshot: until the deadline. After it: until it has been quiet for
      // the settle time (the map publishes its catch-up snapshot when its input stops).
      const auto until = latest ? now + settle : deadline;
      if (now >= deadline && !latest) break;
      const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(until - now);
      std::optional<msg::ExperienceMap> m = maps.TakeOne(std::max(wait, std::chrono::milliseconds(0)));
      if (!m) break;
      if (!latest || m->action_seq >= latest->action_seq) latest = std::move(m);
      if (Clock::now() >= deadline + settle) break;
    }
    if (!latest) spdlog::info("no experience map snapshot within {} s: continuing from the saved state", config_.resync_timeout_s);
    return latest;
  }

  void AdoptSnapshot(const msg::ExperienceMap& map) {
    std::vector<MapExperience> experiences;
    experiences.reserve(map.experiences.size());
    for (size_t i = 0; i < map.experiences.size(); ++i) {
      const msg::Experience& e = map.experiences[i];
      if (e.id != i) {
        context_.Reject("map", "snapshot experience ids are not dense; not resynchronised");
        return;
      }
      experiences.push_back({e.template_id, {e.pc_x, e.pc_y, e.pc_th}});
    }
    std::vector<std::pair<uint32_t, uint32_t>> links;
    links.reserve(map.links.size());
    for (const msg::ExperienceLink& l : map.links) links.emplace_back(l.from_id, l.to_id);

    const bool in_step = map.action_seq + 1 == next_action_seq_ && map.experiences.size() == network_.experience_count();
    if (in_step) {
      spdlog::info("experience map agrees with the saved state (action {}, {} experiences)", map.action_seq,
                   map.experiences.size());
      return;
    }
    try {
      // A restored state's packet is more recent than the current experience's cell.
      network_.AdoptExperienceMap(experiences, links, map.current_experience_id, /*move_packet=*/!state_loaded_);
    } catch (const std::invalid_argument& e) {
      context_.Reject("map", std::string("snapshot not adopted: ") + e.what());
      return;
    }
    spdlog::warn(
        "resynchronised with the experience map: it applied action {} (saved state continues at {}), {} experiences "
        "(saved {}); continuing at action {}",
        map.action_seq, next_action_seq_, map.experiences.size(), experience_count_at_load_, map.action_seq + 1);
    next_action_seq_ = map.action_seq + 1;
    restarted_ = true;
    dirty_ = true;
  }

  // ------------------------------------------------------------------------------------------
  // State

  void LoadState() {
    const std::string path = context_.StateFilePath();
    if (path.empty() || context_.runtime().fresh || !std::filesystem::exists(path)) return;
    proto::NodeState state;
    ReadStateFile(path, kStateKind, kStateVersion, state);  // throws StateFileError when corrupt
    network_.LoadState(state.network());                    // throws when it does not fit
    next_action_seq_ = state.next_action_seq();
    has_last_frame_ = state.has_last_frame();
    last_frame_seq_ = state.last_frame_seq();
    last_stamp_ns_ = state.last_stamp_ns();
    experience_count_at_load_ = network_.experience_count();
    mean_vtrans_mps_ = state.mean_vtrans_mps();
    restarted_ = true;
    state_loaded_ = true;
    bridge_pending_ = true;
    spdlog::info("loaded {}: {} experiences, {} templates, next action {}", path, network_.experience_count(),
                 network_.template_count(), next_action_seq_);
  }

  void SaveState() {
    const std::string path = context_.StateFilePath();
    if (path.empty()) return;
    proto::NodeState state;
    {
      std::lock_guard lock(mutex_);
      if (!dirty_) return;
      *state.mutable_network() = network_.SaveState();
      state.set_next_action_seq(next_action_seq_);
      state.set_has_last_frame(has_last_frame_);
      state.set_last_frame_seq(last_frame_seq_);
      state.set_last_stamp_ns(last_stamp_ns_);
      state.set_mean_vtrans_mps(mean_vtrans_mps_);
      dirty_ = false;
    }
    if (!WriteStateFileOrLog(path, kStateKind, kStateVersion, state)) {
      std::lock_guard lock(mutex_);
      dirty_ = true;  // try again at the next save
    }
  }

  ServiceContext& context_;
  const Config config_;
  std::shared_ptr<bus::Publisher<msg::PoseCellAction>> action_pub_;

  std::mutex mutex_;
  bool stopped_ = false;
  bool resynced_ = false;
  PoseCellNetwork network_;
  Joiner joiner_;
  uint64_t reported_incomplete_ = 0;
  uint64_t frames_without_view_ = 0;  // processed since the last one that had its view
  uint64_t refused_links_ = 0;  // exp_boundary_check, exp_submap_check
  FloorBoundary boundary_;      // the frame's, reused
  uint64_t next_action_seq_ = 0;
  bool has_last_frame_ = false;
  uint64_t last_frame_seq_ = 0;
  int64_t last_stamp_ns_ = 0;
  uint32_t experience_count_at_load_ = 0;
  bool restarted_ = false;             // state loaded or adopted: frames may have been missed
  bool state_loaded_ = false;
  bool bridge_pending_ = false;
  double mean_vtrans_mps_ = 0.0;
  int relocalise_frames_left_ = 0;
  bool dirty_ = true;  // a fresh start saves too, so a restart sees the file
  std::chrono::steady_clock::time_point last_save_;
};

PoseCellsNode::PoseCellsNode(ServiceContext& context, const Config& config)
    : processor_(std::make_unique<Processor>(context, config)) {
  // Inputs are subscribed before the resynchronisation, so frames arriving meanwhile wait in the
  // joiner instead of being lost (the input topics are volatile).
  Processor* p = processor_.get();
  velocity_sub_ = context.Subscribe<msg::Velocity>(bus::topics::kOdometryVelocity,
                                                   [p](const msg::Velocity& m) { p->OnVelocity(m); });
  view_sub_ = context.Subscribe<msg::ViewTemplate>(bus::topics::kTemplatesView,
                                                   [p](const msg::ViewTemplate& m) { p->OnView(m); });
  processor_->Resynchronise();
}

PoseCellsNode::~PoseCellsNode() {
  velocity_sub_.reset();  // no callback runs after this
  view_sub_.reset();
  processor_->Stop();
}

void PoseCellsNode::Tick() { processor_->Tick(); }

}  // namespace rslam::pose_cells
