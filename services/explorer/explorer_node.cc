#include "services/explorer/explorer_node.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "common/math/angle.h"
#include "common/persistence/state_file.h"
#include "services/explorer/exploration_planner.h"
#include "services/explorer/proto/explorer_node_state.pb.h"

namespace rslam::explorer {

namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* kStateKind = "rslam.explorer.ExplorerNodeState";
constexpr uint32_t kStateVersion = 1;

// Why a grid cannot be used, or "" when it can.
std::string GridProblem(const msg::OccupancyGrid& g, int64_t max_cells) {
  if (g.width == 0 || g.height == 0) return "grid has no cells";
  const uint64_t cells = uint64_t{g.width} * g.height;
  if (cells > static_cast<uint64_t>(max_cells))
    return "grid of " + std::to_string(cells) + " cells is larger than max_grid_cells";
  if (g.cells.size() != cells)
    return "grid holds " + std::to_string(g.cells.size()) + " cells, width x height is " + std::to_string(cells);
  if (!std::isfinite(g.resolution_m) || g.resolution_m <= 0) return "grid resolution is not positive";
  if (!std::isfinite(g.origin_x_m) || !std::isfinite(g.origin_y_m)) return "grid origin is not finite";
  for (int8_t c : g.cells)
    if (c < -1 || c > 100) return "grid cell value " + std::to_string(c) + " is outside -1..100";
  return "";
}

msg::MotionKind ToMessageKind(MotionCommand::Kind kind) {
  switch (kind) {
    case MotionCommand::Kind::kRotate: return msg::MotionKind::MOTION_ROTATE;
    case MotionCommand::Kind::kMove: return msg::MotionKind::MOTION_MOVE;
    case MotionCommand::Kind::kPirouette: return msg::MotionKind::MOTION_PIROUETTE;
    case MotionCommand::Kind::kStop: return msg::MotionKind::MOTION_STOP;
  }
  return msg::MotionKind::MOTION_STOP;
}

// The pose after a command that completed as planned.
Pose2D Apply(const Pose2D& p, const MotionCommand& c) {
  switch (c.kind) {
    case MotionCommand::Kind::kRotate: return {p.x, p.y, WrapAngle(p.theta + c.angle_rad)};
    case MotionCommand::Kind::kMove: return Compose(p, {c.distance_m, 0.0, 0.0});
    default: return p;
  }
}

bool SameStatus(const msg::ExplorerStatus& a, const msg::ExplorerStatus& b) {
  return a.state == b.state && a.goal_x_m == b.goal_x_m && a.goal_y_m == b.goal_y_m &&
         a.commands_sent == b.commands_sent && a.goals_set_aside == b.goals_set_aside && a.reason == b.reason;
}


}  // namespace

class ExplorerNode::Controller {
 public:
  Controller(ServiceContext& context, const Config& config)
      : context_(context), config_(config), last_save_(Clock::now()), planner_(config.planner) {
    LoadState();
    command_pub_ = context_.Advertise(bus::topics::kExplorerCommand);
    status_pub_ = context_.Advertise(bus::topics::kExplorerStatus);
    std::lock_guard lock(mutex_);
    PublishStatusIfChanged(/*force=*/true);
  }

  // The callbacks share the controller; the node holds the subscribers and drops them before
  // Stop().
  static std::vector<std::shared_ptr<void>> Subscribe(const std::shared_ptr<Controller>& self) {
    ServiceContext& ctx = self->context_;
    std::vector<std::shared_ptr<void>> subscriptions;
    subscriptions.push_back(ctx.Subscribe<msg::OccupancyGrid>(bus::topics::kOccupancyGrid, [self](const msg::OccupancyGrid& m) {
      self->OnGrid(m);
    }));
    subscriptions.push_back(ctx.Subscribe<msg::ExperiencePose>(bus::topics::kExperienceMapPose, [self](const msg::ExperiencePose& m) {
      self->OnPose(m);
    }));
    subscriptions.push_back(ctx.Subscribe<msg::MotionFeedback>(bus::topics::kMotionFeedback, [self](const msg::MotionFeedback& m) {
      self->OnFeedback(m);
    }));
    return subscriptions;
  }

  // A robot must not go on driving a plan nobody watches any more: an outstanding command is
  // cancelled with STOP, and the status says the explorer stopped.
  void Stop() {
    {
      std::lock_guard lock(mutex_);
      if (awaiting_) {
        Send({MotionCommand::Kind::kStop});
        awaiting_.reset();
      }
      if (state_ == msg::ExplorationState::EXPLORATION_EXPLORING) {
        state_ = msg::ExplorationState::EXPLORATION_STOPPED;
        reason_ = "the explorer service stopped";
        PublishStatusIfChanged();
      }
      stopped_ = true;
    }
    SaveState();
  }

  void Tick() {
    {
      std::lock_guard lock(mutex_);
      if (stopped_) return;
      const auto now = Clock::now();
      if (awaiting_ && now - awaiting_->last_heard > Seconds(config_.feedback_timeout_s)) {
        reason_ = "no feedback for command " + std::to_string(awaiting_->seq) + " within " +
                  std::to_string(config_.feedback_timeout_s) + " s: planning again";
        spdlog::warn("{}", reason_);
        awaiting_.reset();
        plan_.reset();
        Step();
      }
      if (fresh_grid_needed_ && now - fresh_grid_since_ > Seconds(config_.fresh_grid_timeout_s)) {
        fresh_grid_needed_ = false;
        Step();
      }
    }
    if (Clock::now() - last_save_ >= Seconds(context_.runtime().state_save_period_s)) {
      last_save_ = Clock::now();
      SaveState();
    }
  }

 private:
  struct Outstanding {
    uint64_t seq = 0;
    MotionCommand command;
    Clock::time_point last_heard;
  };

  static Clock::duration Seconds(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }

  void OnGrid(const msg::OccupancyGrid& grid) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    if (const std::string problem = GridProblem(grid, config_.max_grid_cells); !problem.empty()) {
      context_.Reject("grid", problem);
      return;
    }
    if (!grid_ || grid_->resolution_m != grid.resolution_m)
      spdlog::info("exploring on {:.3f}-m cells: coarse_cell_factor {} x the grid's {:.3f}-m cells",
                   grid.resolution_m * config_.planner.coarse_cell_factor, config_.planner.coarse_cell_factor,
                   grid.resolution_m);
    grid_ = grid;
    fresh_grid_needed_ = false;
    Step();
  }

  void OnPose(const msg::ExperiencePose& pose) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    if (!std::isfinite(pose.x_m) || !std::isfinite(pose.y_m) || !std::isfinite(pose.theta_rad)) {
      context_.Reject("pose", "robot pose has a non-finite number");
      return;
    }
    const bool first = !pose_;
    pose_ = pose;
    context_.SetLastFrame(pose.header.frame_seq, pose.header.stamp_ns);
    if (first) Step();
  }

  void OnFeedback(const msg::MotionFeedback& feedback) {
    std::lock_guard lock(mutex_);
    if (stopped_ || !awaiting_ || feedback.command_seq != awaiting_->seq) return;  // not ours or old
    switch (feedback.state) {
      case msg::MotionState::MOTION_EXECUTING:
        awaiting_->last_heard = Clock::now();
        return;
      case msg::MotionState::MOTION_DONE: {
        const MotionCommand done = awaiting_->command;
        awaiting_.reset();
        const Pose2D from = std::exchange(expected_pose_, Apply(expected_pose_, done));
        ++next_command_;
        if (done.kind == MotionCommand::Kind::kMove) planner_.RecordMove(from, expected_pose_);
        if (done.kind == MotionCommand::Kind::kPirouette && pose_) planner_.RecordPirouette(RobotPose());
        // The next plan needs the grid of what the robot just saw: after a pirouette, and after
        // the last move of a plan that ends without one (pirouette_at_goal false).
        if (done.kind == MotionCommand::Kind::kPirouette || (plan_ && next_command_ >= plan_->commands.size()))
          WaitForFreshGrid();
        Step();
        return;
      }
      case msg::MotionState::MOTION_BLOCKED: {
        // A blocked straight move bumped into something the map does not show (ReportBump).
        const bool bumped = awaiting_->command.kind == MotionCommand::Kind::kMove && pose_;
        const bool backwards = awaiting_->command.distance_m < 0;
        awaiting_.reset();
        if (bumped) {
          const Pose2D at = RobotPose();
          spdlog::info("the base stopped command {} short: bumped at ({:.2f}, {:.2f}, {:.2f})", feedback.command_seq,
                       at.x, at.y, at.theta);
          planner_.RecordMove(expected_pose_, at);
          if (plan_) planner_.ReportBump(*plan_, at, backwards);
        } else {
          spdlog::info("the base stopped command {} short", feedback.command_seq);
          if (plan_) planner_.ReportBlocked(*plan_);
        }
        plan_.reset();
        reason_ = "the base reported command " + std::to_string(feedback.command_seq) + " blocked";
        NoteSetAside();
        WaitForFreshGrid();
        Step();
        return;
      }
    }
    context_.Reject("feedback", "unknown motion state " + std::to_string(static_cast<int>(feedback.state)));
  }

  void WaitForFreshGrid() {
    fresh_grid_needed_ = true;
    fresh_grid_since_ = Clock::now();
  }

  Pose2D RobotPose() const { return {pose_->x_m, pose_->y_m, pose_->theta_rad}; }

  GridView View() const {
    GridView view;
    view.width = static_cast<int>(grid_->width);
    view.height = static_cast<int>(grid_->height);
    view.resolution_m = grid_->resolution_m;
    view.origin_x_m = grid_->origin_x_m;
    view.origin_y_m = grid_->origin_y_m;
    view.cells = grid_->cells;
    view.free_max_percent = config_.free_max_percent;
    view.occupied_min_percent = config_.occupied_min_percent;
    return view;
  }

  // Decides and sends the next command when none is outstanding. Called with the mutex held.
  void Step() {
    if (stopped_ || state_ == msg::ExplorationState::EXPLORATION_COMPLETE || awaiting_) return;
    if (!grid_ || !pose_ || fresh_grid_needed_) {
      PublishStatusIfChanged();
      return;
    }
    const GridView view = View();
    if (!plan_ || next_command_ >= plan_->commands.size()) {
      try {
        plan_ = planner_.PlanFrom(view, RobotPose());
      } catch (const std::exception& e) {  // robot off the map, or a planner bug: say so, wait
        plan_.reset();
        reason_ = std::string("cannot plan: ") + e.what();
        PublishStatusIfChanged();
        return;
      }
      next_command_ = 0;
      expected_pose_ = RobotPose();
      NoteSetAside();
      if (plan_->complete) {
        Complete(plan_->reason);
        return;
      }
      state_ = msg::ExplorationState::EXPLORATION_EXPLORING;
      if (plan_->goal_x >= 0) {
        const double cell = grid_->resolution_m * planner_.cell_factor();
        goal_x_m_ = grid_->origin_x_m + (plan_->goal_x + 0.5) * cell;
        goal_y_m_ = grid_->origin_y_m + (plan_->goal_y + 0.5) * cell;
      }
      spdlog::info("plan: {} ({} commands) towards ({:.2f}, {:.2f})", plan_->reason, plan_->commands.size(),
                   goal_x_m_, goal_y_m_);
    }
    const MotionCommand& command = plan_->commands[next_command_];
    const auto obstacle = command.kind == MotionCommand::Kind::kMove && !plan_->way_back
                              ? planner_.ObstacleOnPath(view, expected_pose_, command.distance_m)
                              : std::nullopt;
    if (obstacle) {
      // Look before you move: the latest grid shows an obstacle on the way.
      spdlog::info("blocked: move {:.2f} m from ({:.2f}, {:.2f}, {:.2f}) passes the obstacle at ({:.3f}, {:.3f})",
                   command.distance_m, expected_pose_.x, expected_pose_.y, expected_pose_.theta, obstacle->first,
                   obstacle->second);
      planner_.ReportBlocked(*plan_, obstacle);
      plan_.reset();
      reason_ = "look before you move: the path ahead is blocked, planning again";
      NoteSetAside();
      // The same grid would give the same plan: look again with the next one.
      WaitForFreshGrid();
      PublishStatusIfChanged();
      return;
    }
    Send(command);
    PublishStatusIfChanged();
  }

  void Send(const MotionCommand& command) {
    msg::MotionCommand out;
    if (pose_) out.header = pose_->header;
    out.header.robot_id = context_.robot_id();
    out.command_seq = ++command_seq_;
    out.kind = ToMessageKind(command.kind);
    out.angle_rad = command.angle_rad;  // kPirouette: one of its turns
    out.distance_m = command.distance_m;
    command_pub_->Publish(out);
    ++commands_sent_;
    dirty_ = true;
    if (command.kind != MotionCommand::Kind::kStop) awaiting_ = Outstanding{out.command_seq, command, Clock::now()};
  }

  void Complete(std::string reason) {  // by value: it often comes from plan_, reset below
    Send({MotionCommand::Kind::kStop});
    state_ = msg::ExplorationState::EXPLORATION_COMPLETE;
    plan_.reset();
    spdlog::info("exploration complete: {}", reason);
    reason_ = std::move(reason);
    PublishStatusIfChanged();
  }

  // Logs the goals the planner has newly set aside, with their reason (a run of cells with the same
  // reason on one line), and the goals it tries again.
  void NoteSetAside() {
    const auto& goals = planner_.set_aside_goals();
    const auto [sx, sy] = planner_.cells_shift();  // the logged goals onto the grid's cells, as the planner's
    for (SetAsideGoal& g : logged_set_aside_) g.x += sx - logged_shift_.first, g.y += sy - logged_shift_.second;
    logged_shift_ = {sx, sy};
    const auto listed = [](const std::vector<SetAsideGoal>& list, const SetAsideGoal& g) {
      return std::any_of(list.begin(), list.end(), [&](const SetAsideGoal& o) { return o.x == g.x && o.y == g.y; });
    };
    const auto and_more = [](size_t n) { return n > 1 ? " and " + std::to_string(n - 1) + " more" : std::string(); };
    std::vector<SetAsideGoal> retried, fresh;
    std::copy_if(logged_set_aside_.begin(), logged_set_aside_.end(), std::back_inserter(retried),
                 [&](const SetAsideGoal& g) { return !listed(goals, g); });
    std::copy_if(goals.begin(), goals.end(), std::back_inserter(fresh),
                 [&](const SetAsideGoal& g) { return !listed(logged_set_aside_, g); });
    if (!retried.empty())
      spdlog::info("trying again goal cell ({}, {}){}", retried[0].x, retried[0].y, and_more(retried.size()));
    for (size_t i = 0, j = 0; i < fresh.size(); i = j) {
      while (j < fresh.size() && fresh[j].reason == fresh[i].reason) ++j;
      const std::string cells =
          "goal cell (" + std::to_string(fresh[i].x) + ", " + std::to_string(fresh[i].y) + ")" + and_more(j - i);
      spdlog::warn("set aside {}: {}", cells, fresh[i].reason);
      reason_ = "set aside " + cells + ": " + fresh[i].reason;
      dirty_ = true;
    }
    logged_set_aside_ = goals;
  }

  void PublishStatusIfChanged(bool force = false) {
    msg::ExplorerStatus status;
    if (pose_) status.header = pose_->header;
    status.header.robot_id = context_.robot_id();
    status.state = state_;
    status.goal_x_m = goal_x_m_;
    status.goal_y_m = goal_y_m_;
    status.commands_sent = commands_sent_;
    status.goals_set_aside = static_cast<uint32_t>(planner_.set_aside_goals().size());
    status.reason = reason_;
    if (!force && last_status_ && SameStatus(*last_status_, status)) return;
    status_pub_->Publish(status);
    last_status_ = status;
  }

  void LoadState() {
    const std::string path = context_.StateFilePath();
    if (path.empty() || context_.runtime().fresh || !std::filesystem::exists(path)) return;
    proto::ExplorerNodeState state;
    ReadStateFile(path, kStateKind, kStateVersion, state);  // throws StateFileError when corrupt
    planner_.LoadProto(state.planner());                     // validates the whole message
    command_seq_ = state.last_command_seq();
    logged_set_aside_ = planner_.set_aside_goals();
    spdlog::info("loaded explorer state from {}: {} goals set aside, last command {}", path,
                 logged_set_aside_.size(), command_seq_);
  }

  void SaveState() {
    const std::string path = context_.StateFilePath();
    if (path.empty()) return;
    proto::ExplorerNodeState state;
    {
      std::lock_guard lock(mutex_);
      if (!dirty_) return;
      *state.mutable_planner() = planner_.ToProto();
      state.set_last_command_seq(command_seq_);
      dirty_ = false;
    }
    if (!WriteStateFileOrLog(path, kStateKind, kStateVersion, state)) {
      std::lock_guard lock(mutex_);
      dirty_ = true;  // try again at the next save
    }
  }

  ServiceContext& context_;
  const Config config_;
  std::shared_ptr<bus::Publisher<msg::MotionCommand>> command_pub_;
  std::shared_ptr<bus::Publisher<msg::ExplorerStatus>> status_pub_;
  Clock::time_point last_save_;

  std::mutex mutex_;
  bool stopped_ = false;
  bool dirty_ = true;
  ExplorationPlanner planner_;
  std::optional<msg::OccupancyGrid> grid_;
  std::optional<msg::ExperiencePose> pose_;
  std::optional<Plan> plan_;
  size_t next_command_ = 0;
  Pose2D expected_pose_;  // where the robot should be if the plan's commands so far went as planned
  std::optional<Outstanding> awaiting_;
  bool fresh_grid_needed_ = false;
  Clock::time_point fresh_grid_since_;
  uint64_t command_seq_ = 0;
  uint32_t commands_sent_ = 0;
  std::vector<SetAsideGoal> logged_set_aside_;
  std::pair<int, int> logged_shift_{0, 0};  // the planner's cells_shift when they were logged
  msg::ExplorationState state_ = msg::ExplorationState::EXPLORATION_WAITING;
  double goal_x_m_ = 0.0, goal_y_m_ = 0.0;
  std::string reason_ = "waiting for a grid and a pose";
  std::optional<msg::ExplorerStatus> last_status_;
};

ExplorerNode::ExplorerNode(ServiceContext& context, const Config& config)
    : controller_(std::make_shared<Controller>(context, config)) {
  subscriptions_ = Controller::Subscribe(controller_);
}

ExplorerNode::~ExplorerNode() {
  subscriptions_.clear();  // no callback runs after this
  controller_->Stop();
}

void ExplorerNode::Tick() { controller_->Tick(); }

}  // namespace rslam::explorer
