#include "tools/sim/sim_node.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "common/config/config_error.h"
#include "common/node/shutdown_signal.h"

namespace rslam::sim {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::chrono::nanoseconds Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(s));
}

// The largest turn or move a command may ask for: anything beyond is a planner bug, not a plan.
constexpr double kMaxAbsAngleRad = 8 * M_PI;
constexpr double kMaxAbsDistanceM = 1000.0;

}  // namespace

std::string ResolveWorldPath(const std::string& world_yaml) {
  const fs::path path(world_yaml);
  if (path.is_absolute() || fs::exists(path)) return path.string();
#ifdef RSLAM_SOURCE_DIR
  const fs::path in_tree = fs::path(RSLAM_SOURCE_DIR) / path;
  if (fs::exists(in_tree)) return in_tree.string();
#endif
  return path.string();  // loading reports the missing file
}

Pose2D StartPoseOf(const SimNodeConfig& config, const WorldMap& world) {
  if (config.start_pose.size() == 3) return Pose2D{config.start_pose[0], config.start_pose[1], config.start_pose[2]};
  return world.DefaultStartPose();
}

namespace {

WorldMap LoadWorld(const std::string& world_yaml) {
  try {
    return WorldMap::LoadFromYaml(ResolveWorldPath(world_yaml));
  } catch (const WorldFileError& e) {
    throw ConfigError("sim.world_yaml", e.what());
  }
}

}  // namespace

SimNode::SimNode(ServiceContext& context, const Config& config)
    : context_(context),
      config_(config),
      world_(LoadWorld(config.sim.world_yaml)),
      robot_([&]() -> SimulatedRobot {
        // Guaranteed copy elision: the robot is built in place.
        try {
          return SimulatedRobot(world_, config_.sim, StartPoseOf(config_, world_));
        } catch (const std::invalid_argument& e) {
          throw ConfigError("sim.start_pose", e.what());
        }
      }()),
      links_(context.participant()),
      pacer_(static_cast<int>(config.lockstep_topics.size()), config.max_frames_in_flight,
             Seconds(config.lockstep_timeout_s), Seconds(config.startup_timeout_s)) {
  camera_pub_ = context_.Advertise(bus::topics::kSimCamera);
  ground_truth_pub_ = context_.Advertise(bus::topics::kGroundTruth);
  wheel_odometry_pub_ = context_.Advertise(bus::topics::kWheelOdometry);
  feedback_pub_ = context_.Advertise(bus::topics::kMotionFeedback);
  command_sub_ = context_.Subscribe<msg::MotionCommand>(bus::topics::kExplorerCommand,
                                                        [this](const msg::MotionCommand& c) { OnCommand(c); });
  if (config_.rate_hz == 0) SubscribeLockstepTopics();
  const Pose2D start = robot_.pose();
  spdlog::info("world {} ({}x{} cells of {} m), start ({:.2f}, {:.2f}, {:.2f}), {}", config_.sim.world_yaml,
               world_.width(), world_.height(), world_.resolution(), start.x, start.y, start.theta,
               config_.rate_hz > 0 ? fmt::format("{} Hz", config_.rate_hz)
                                   : fmt::format("lockstep ({} frames in flight)", config_.max_frames_in_flight));
  thread_ = std::thread([this] { Run(); });
}

SimNode::~SimNode() {
  // Subscriber callbacks use the mutex: end them before anything else goes.
  command_sub_.reset();
  lockstep_matched_.clear();
  lockstep_subs_.clear();
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  spdlog::info("published {} frames", frames_published_.load());
}

std::vector<std::string> SimNode::UnlinkedServices() const {
  return links_.Unmatched(config_.wait_for_services,
                          config_.rate_hz == 0 ? config_.lockstep_topics : std::vector<std::string>{});
}

void SimNode::SubscribeLockstepTopics() {
  for (size_t i = 0; i < config_.lockstep_topics.size(); ++i) {
    const std::string& name = config_.lockstep_topics[i];
    const int stage = static_cast<int>(i);
    auto report = [this, stage](const auto& m) { OnStageReport(stage, m.header.frame_seq); };
    auto add = [&](auto topic) {
      using T = typename decltype(topic)::Type;
      auto sub = context_.Subscribe<T>(topic, report);
      lockstep_matched_.push_back([sub] { return sub->MatchedPublishers(); });
      lockstep_subs_.push_back(std::move(sub));
    };
    namespace t = bus::topics;
    if (name == t::kCameraImage.name) {
      add(t::kCameraImage);
    } else if (name == t::kOdometryVelocity.name) {
      add(t::kOdometryVelocity);
    } else if (name == t::kTemplatesView.name) {
      add(t::kTemplatesView);
    } else if (name == t::kPoseCellsAction.name) {
      add(t::kPoseCellsAction);
    } else if (name == t::kExperienceMapPose.name) {
      add(t::kExperienceMapPose);
    } else if (name == t::kOccupancyProfile.name) {
      add(t::kOccupancyProfile);
    } else {
      throw ConfigError("sim.lockstep_topics", "unknown per-frame topic '" + name + "'");
    }
  }
}

void SimNode::OnStageReport(int stage, uint64_t frame_seq) {
  {
    std::lock_guard lock(mutex_);
    pacer_.Report(stage, frame_seq, Clock::now());
  }
  wake_.notify_all();
}

void SimNode::OnCommand(const msg::MotionCommand& c) {
  PendingCommand pending;
  pending.command_seq = c.command_seq;
  switch (c.kind) {
    case msg::MotionKind::MOTION_STOP:
      pending.command = MotionCommand::Stop();
      break;
    case msg::MotionKind::MOTION_ROTATE:
      if (!std::isfinite(c.angle_rad) || std::abs(c.angle_rad) > kMaxAbsAngleRad) {
        context_.Reject("command", fmt::format("rotate command {} with angle {} (must be finite, |a| <= 8 pi)",
                                               c.command_seq, c.angle_rad));
        return;
      }
      pending.command = MotionCommand::Rotate(c.angle_rad);
      break;
    case msg::MotionKind::MOTION_MOVE:
      if (!std::isfinite(c.distance_m) || std::abs(c.distance_m) > kMaxAbsDistanceM) {
        context_.Reject("command", fmt::format("move command {} with distance {} (must be finite, |d| <= 1000 m)",
                                               c.command_seq, c.distance_m));
        return;
      }
      pending.command = MotionCommand::Move(c.distance_m);
      break;
    case msg::MotionKind::MOTION_PIROUETTE:
      pending.command = MotionCommand::Pirouette();
      break;
    default:
      context_.Reject("command", fmt::format("command {} of unknown kind {}", c.command_seq, static_cast<int>(c.kind)));
      return;
  }
  {
    std::lock_guard lock(mutex_);
    pending_.push_back(pending);
  }
  wake_.notify_all();
}

bool SimNode::WaitForSlot(uint64_t frame_seq, Clock::time_point slot) {
  std::unique_lock lock(mutex_);
  if (config_.rate_hz > 0) {
    wake_.wait_until(lock, slot, [this] { return stop_; });
    return !stop_;
  }
  pacer_.Start(Clock::now());
  // The pacer's answer changes with reports (which wake us) and with time (timeouts): poll too.
  // Past a silent or missing stage the sim keeps real time (one frame per time step), as a robot
  // would: flat out it would flood the stages that are there and they could never catch up.
  const auto real_time_slot = last_frame_time_ + Seconds(config_.sim.motion.time_step_s);
  while (!stop_) {
    const auto now = Clock::now();
    if (pacer_.MayPublish(frame_seq, now) &&
        (!pacer_.PassingAbsentStage(frame_seq, now) || now >= real_time_slot))
      break;
    wake_.wait_for(lock, std::chrono::milliseconds(5));
  }
  last_frame_time_ = Clock::now();
  return !stop_;
}

void SimNode::PublishFeedback(const msg::Header& header, uint64_t command_seq, msg::MotionState state) {
  msg::MotionFeedback feedback;
  feedback.header = header;
  feedback.command_seq = command_seq;
  feedback.state = state;
  feedback_pub_->Publish(feedback);
}

void SimNode::ApplyPendingCommands(const msg::Header& header) {
  std::deque<PendingCommand> commands;
  {
    std::lock_guard lock(mutex_);
    commands.swap(pending_);
  }
  for (const PendingCommand& p : commands) {
    robot_.Command(p.command);
    PublishFeedback(header, p.command_seq, msg::MotionState::MOTION_EXECUTING);
    if (p.command.kind == MotionCommand::Kind::kStop) {
      PublishFeedback(header, p.command_seq, msg::MotionState::MOTION_DONE);
      running_command_seq_.reset();
    } else {
      running_command_seq_ = p.command_seq;  // a newer command replaces the running one
    }
  }
}

void SimNode::PublishFrame(const SimFrame& frame, const msg::Header& header) {
  const cv::Mat& image = frame.image;
  image_msg_.header = header;
  image_msg_.width = static_cast<uint32_t>(image.cols);
  image_msg_.height = static_cast<uint32_t>(image.rows);
  image_msg_.encoding = "bgr8";
  image_msg_.step = static_cast<uint32_t>(image.cols * 3);
  image_msg_.data.resize(static_cast<size_t>(image.rows) * image_msg_.step);
  for (int r = 0; r < image.rows; ++r)
    std::memcpy(image_msg_.data.data() + static_cast<size_t>(r) * image_msg_.step, image.ptr(r), image_msg_.step);
  camera_pub_->Publish(image_msg_);

  msg::GroundTruthPose truth;
  truth.header = header;
  truth.x_m = frame.ground_truth.x;
  truth.y_m = frame.ground_truth.y;
  truth.theta_rad = frame.ground_truth.theta;
  ground_truth_pub_->Publish(truth);

  msg::Velocity wheel;
  wheel.header = header;
  wheel.vtrans_mps = frame.wheel_odometry.vtrans_mps;
  wheel.vrot_radps = frame.wheel_odometry.vrot_radps;
  wheel.dt_s = frame.wheel_odometry.dt_s;
  wheel.source = msg::VelocitySource::VELOCITY_WHEEL;
  wheel_odometry_pub_->Publish(wheel);
}

void SimNode::Run() {
  try {
    // Frames published before the pipeline listens are lost, and in lockstep a lost frame stalls
    // the start until the startup timeout: wait for the camera service to read sim/camera, for
    // the lockstep stages to publish, and for the heartbeats to show the services in between
    // matched to each other.
    auto pipeline_ready = [this] {
      if (camera_pub_->MatchedSubscribers() < 1) return false;
      for (const auto& matched : lockstep_matched_)
        if (matched() < 1) return false;
      return UnlinkedServices().empty();
    };
    const auto wait_start = Clock::now();
    const auto pipeline_deadline = wait_start + Seconds(config_.wait_for_pipeline_s);
    while (config_.wait_for_pipeline_s > 0 && !pipeline_ready()) {
      if (Clock::now() >= pipeline_deadline) {
        spdlog::warn("pipeline not (fully) there after {} s; publishing anyway (camera readers {}; {})",
                     config_.wait_for_pipeline_s, camera_pub_->MatchedSubscribers(),
                     fmt::join(UnlinkedServices(), "; "));
        break;
      }
      std::unique_lock lock(mutex_);
      if (wake_.wait_for(lock, std::chrono::milliseconds(20), [this] { return stop_; })) return;
    }
    spdlog::info("first frame after {:.2f} s waiting for the pipeline",
                 std::chrono::duration<double>(Clock::now() - wait_start).count());
    const double dt = config_.sim.motion.time_step_s;
    const auto rate_start = Clock::now();
    SimFrame frame;
    while (true) {
      const uint64_t n = robot_.next_frame_index();
      if (config_.max_frames > 0 && n >= static_cast<uint64_t>(config_.max_frames)) {
        spdlog::info("published max_frames = {}; stopping", config_.max_frames);
        RequestShutdown();
        return;
      }
      const auto slot = config_.rate_hz > 0 ? rate_start + Seconds(static_cast<double>(n) / config_.rate_hz)
                                            : Clock::time_point{};
      if (!WaitForSlot(n, slot)) return;
      msg::Header header;
      header.robot_id = context_.robot_id();
      header.frame_seq = n;
      header.stamp_ns = config_.start_stamp_ns + static_cast<int64_t>(std::llround(static_cast<double>(n) * dt * 1e9));
      try {
        ApplyPendingCommands(header);
        robot_.Tick(&frame);
        PublishFrame(frame, header);
        if (frame.motion.command_finished && running_command_seq_) {
          PublishFeedback(header, *running_command_seq_,
                          frame.motion.blocked ? msg::MotionState::MOTION_BLOCKED : msg::MotionState::MOTION_DONE);
          running_command_seq_.reset();
        }
      } catch (const bus::BusError& e) {
        // A reader that stays blocked: the frame is lost for it, the world goes on.
        spdlog::warn("frame {}: {}", n, e.what());
      }
      context_.SetLastFrame(n, header.stamp_ns);
      ++frames_published_;
      {
        std::lock_guard lock(mutex_);
        last_pose_ = frame.ground_truth;
      }
    }
  } catch (const std::exception& e) {
    spdlog::error("simulation stopped: {}", e.what());
    RequestShutdown();
  }
}

void SimNode::Tick() {
  if (++ticks_ % 10 != 0) return;
  Pose2D pose;
  {
    std::lock_guard lock(mutex_);
    pose = last_pose_;
  }
  spdlog::info("{} frames, robot at ({:.2f}, {:.2f}, {:.2f})", frames_published_.load(), pose.x, pose.y, pose.theta);
}

}  // namespace rslam::sim
