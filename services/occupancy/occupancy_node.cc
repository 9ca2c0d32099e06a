#include "services/occupancy/occupancy_node.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <stop_token>
#include <string>
#include <thread>
#include <unordered_map>

#include "common/persistence/state_file.h"
#include "services/occupancy/anchored_profile_map.h"
#include "services/occupancy/frame_joiner.h"
#include "services/occupancy/grid_export.h"
#include "services/occupancy/obstacle_profile_pipeline.h"
#include "services/occupancy/profile_message.h"

namespace rslam::occupancy {

namespace {

constexpr const char* kStateKind = "rslam.occupancy.OccupancyState";
constexpr uint32_t kStateVersion = 1;

// Why an image cannot be used, or "" when it can.
std::string ImageProblem(const msg::Image& image, const CameraConfig& camera) {
  int channels = 0;
  if (image.encoding == "bgr8") channels = 3;
  else if (image.encoding == "mono8") channels = 1;
  else return "unknown encoding '" + image.encoding.substr(0, 32) + "' (bgr8 or mono8)";
  if (image.width != static_cast<uint32_t>(camera.width) || image.height != static_cast<uint32_t>(camera.height))
    return "image is " + std::to_string(image.width) + "x" + std::to_string(image.height) + ", the camera is " +
           std::to_string(camera.width) + "x" + std::to_string(camera.height);
  if (uint64_t{image.step} < uint64_t{image.width} * channels)
    return "step " + std::to_string(image.step) + " is shorter than a row";
  if (uint64_t{image.step} * image.height != image.data.size())
    return "data holds " + std::to_string(image.data.size()) + " bytes, step x height is " +
           std::to_string(uint64_t{image.step} * image.height);
  return "";
}

bool IsFinitePose(const msg::ExperiencePose& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad) &&
         std::isfinite(p.experience_x_m) && std::isfinite(p.experience_y_m) && std::isfinite(p.experience_theta_rad);
}

}  // namespace

class OccupancyNode::Mapper {
 public:
  Mapper(ServiceContext& context, const Config& config)
      : context_(context),
        config_(config),
        pipeline_(config.pipeline),
        map_(config.grid, config.sensor, config.profile_alignment),
        joiner_(static_cast<size_t>(config.join_buffer_frames)),
        last_save_(std::chrono::steady_clock::now()) {
    LoadState();
    profile_pub_ = context_.Advertise(bus::topics::kOccupancyProfile);
    grid_pub_ = context_.Advertise(bus::topics::kOccupancyGrid);
    if (!map_.profiles().empty()) {
      // A restarted mapper shows its restored grid at once (state QoS: late joiners get it too).
      std::lock_guard lock(mutex_);
      last_header_.robot_id = context_.robot_id();
      PublishGrid(last_header_, grid_map_version_);
    }
  }

  // Subscriptions are made once the mapper is owned by a shared_ptr, which the callbacks share;
  // the node holds the subscribers and drops them before Stop().
  static std::vector<std::shared_ptr<void>> Subscribe(const std::shared_ptr<Mapper>& self) {
    ServiceContext& ctx = self->context_;
    std::vector<std::shared_ptr<void>> subscriptions;
    subscriptions.push_back(ctx.Subscribe<msg::Image>(bus::topics::kCameraImage,
                              [self](const msg::Image& m) { self->OnImage(m); }));
    subscriptions.push_back(ctx.Subscribe<msg::ExperiencePose>(bus::topics::kExperienceMapPose, [self](const msg::ExperiencePose& m) {
      self->OnPose(m);
    }));
    subscriptions.push_back(ctx.Subscribe<msg::ExperienceMap>(bus::topics::kExperienceMapMap, [self](const msg::ExperienceMap& m) {
      self->OnMap(m);
    }));
    return subscriptions;
  }

  ~Mapper() { StopRebuilds(); }

  // Stops processing and saves every kept profile before anything slow, then brings the grid onto
  // the newest map: a rebuild of an older map still under way is dropped for it, so the stop
  // replays once (a long demo run's rebuild took 3-6 s, and finishing one and then the newest ran
  // past the 5-s stop deadline). Then saves the anchors the rebuild moved and exports the grid.
  // If the deadline ends the stop during the rebuild, the state file still holds every profile.
  void Stop() {
    const auto start = std::chrono::steady_clock::now();
    {
      std::lock_guard lock(mutex_);
      stopped_ = true;
      if (planned_rebuild_ && pending_correction_) planned_rebuild_->stop.request_stop();
      ApplyPendingCorrection();  // when a rebuild is under way, the loop plans this after it
    }
    SaveState();
    StopRebuilds();
    if (config_.profile_alignment.window_m > 0)
      spdlog::info("{} of {} kept profiles were aligned with the grid", map_.AlignedProfiles(), map_.profiles().size());
    SaveState();
    ExportMaps();
    spdlog::info("stopped: {} kept profiles saved, the grid on map version {}, in {:.2f} s", map_.profiles().size(),
                 grid_map_version_, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }

  void Tick() {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_save_ < std::chrono::duration<double>(context_.runtime().state_save_period_s)) return;
    last_save_ = now;
    SaveState();
  }

 private:
  void OnImage(const msg::Image& image) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    if (const std::string problem = ImageProblem(image, config_.pipeline.camera); !problem.empty()) {
      context_.Reject("image", problem);
      return;
    }
    auto joined = joiner_.AddA(image.header.frame_seq, image);
    CountDropped();
    if (joined) ProcessFrame(joined->a, joined->b);
  }

  void OnPose(const msg::ExperiencePose& pose) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    if (!IsFinitePose(pose)) {
      context_.Reject("pose", "experience pose has a non-finite number");
      return;
    }
    auto joined = joiner_.AddB(pose.header.frame_seq, pose);
    CountDropped();
    if (joined) ProcessFrame(joined->a, joined->b);
  }

  void OnMap(const msg::ExperienceMap& map) {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    PendingCorrection correction;
    correction.map_version = map.map_version;
    correction.poses.reserve(map.experiences.size());
    for (const msg::Experience& e : map.experiences) {
      if (!std::isfinite(e.x_m) || !std::isfinite(e.y_m) || !std::isfinite(e.theta_rad)) {
        context_.Reject("map", "experience " + std::to_string(e.id) + " has a non-finite pose");
        return;
      }
      correction.poses[e.id] = {e.x_m, e.y_m, e.theta_rad};
    }
    if (rebuilt_version_ && map.map_version <= *rebuilt_version_) return;
    if (pending_correction_ && map.map_version <= pending_correction_->map_version) return;
    pending_correction_ = std::move(correction);
    if (RebuildDue()) ApplyPendingCorrection();
  }

  // A rebuild replays every profile: while the map keeps correcting, do it at most once every
  // rebuild_at_most_every_n_frames frames and within rebuild_max_busy_share of the time (the
  // newest correction waits for a later frame); on stopping, at once.
  bool RebuildDue() const {
    return stopped_ || (frames_since_rebuild_ >= config_.rebuild_at_most_every_n_frames &&
                        std::chrono::steady_clock::now() >= rebuild_not_before_);
  }

  // Starts a rebuild for the pending correction unless one is under way (the newest correction
  // then waits for it). The replay runs on the rebuild thread, so frames keep flowing meanwhile:
  // in the lockstep demo every frame waits for occupancy/profile, and replaying every profile on
  // the frame's thread held the whole pipeline for 136 ms at 20,000 profiles.
  void ApplyPendingCorrection() {
    if (!pending_correction_ || planned_rebuild_) return;
    const PendingCorrection correction = std::move(*pending_correction_);
    pending_correction_.reset();
    rebuilt_version_ = correction.map_version;
    if (!grid_behind_anchors_ && !AnchorsMoved(correction.poses)) {
      grid_map_version_ = std::max(grid_map_version_, correction.map_version);
      return;
    }
    const auto lookup = [&correction](uint64_t id) -> std::optional<Pose2D> {
      if (auto it = correction.poses.find(id); it != correction.poses.end()) return it->second;
      return std::nullopt;
    };
    planned_rebuild_.emplace(map_.PlanRebuild(lookup), correction.map_version);
    grid_behind_anchors_ = true;  // until the plan's grid is adopted
    frames_since_rebuild_ = 0;
    if (!rebuild_thread_.joinable()) rebuild_thread_ = std::thread([this] { RebuildLoop(); });
    rebuild_wake_.notify_one();
  }

  void RebuildLoop() {
    std::unique_lock lock(mutex_);
    for (;;) {
      rebuild_wake_.wait(lock, [this] { return planned_rebuild_ || stop_rebuilds_; });
      if (!planned_rebuild_) return;  // stopping, nothing planned
      // Nothing else writes the plan while it is set (ApplyPendingCorrection waits for the reset).
      PlannedRebuild& job = *planned_rebuild_;
      lock.unlock();
      const auto start = std::chrono::steady_clock::now();
      std::optional<OccupancyGrid> grid = AnchoredProfileMap::Replay(job.plan, job.stop.get_token());
      const auto end = std::chrono::steady_clock::now();
      lock.lock();
      if (!grid) {  // stopped for a newer map (Stop): the anchors the plan moved are not in the grid
        spdlog::info("map version {}: rebuild dropped for map version {}", job.map_version,
                     pending_correction_ ? pending_correction_->map_version : 0);
        planned_rebuild_.reset();
        ApplyPendingCorrection();
        continue;
      }
      rebuild_not_before_ = end + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      (end - start) * (1.0 / config_.rebuild_max_busy_share - 1.0));
      map_.Adopt(std::move(*grid), job.plan);
      grid_behind_anchors_ = false;
      const uint64_t version = job.map_version;
      grid_map_version_ = std::max(grid_map_version_, version);
      dirty_ = true;
      spdlog::info("map version {}: rebuilt the grid ({} of {} profiles moved)", version, job.plan.moved,
                   job.plan.placements.size());
      planned_rebuild_.reset();
      PublishGrid(last_header_, version);  // on stopping too: subscribers get the grid that is saved
      if (RebuildDue()) ApplyPendingCorrection();
    }
  }

  void StopRebuilds() {
    {
      std::lock_guard lock(mutex_);
      stop_rebuilds_ = true;
    }
    rebuild_wake_.notify_one();
    if (rebuild_thread_.joinable()) rebuild_thread_.join();
  }

  bool AnchorsMoved(const std::unordered_map<uint64_t, Pose2D>& poses) const {
    for (const AnchoredProfile& p : map_.profiles()) {
      auto it = poses.find(p.experience_id);
      if (it == poses.end()) continue;
      const Pose2D& now = it->second;
      if (std::hypot(now.x - p.experience_pose.x, now.y - p.experience_pose.y) >= config_.rebuild_min_shift_m ||
          std::abs(WrapAngle(now.theta - p.experience_pose.theta)) >= config_.rebuild_min_turn_rad)
        return true;
    }
    return false;
  }

  void ProcessFrame(const msg::Image& image, const msg::ExperiencePose& pose) {
    const int type = image.encoding == "bgr8" ? CV_8UC3 : CV_8UC1;
    const cv::Mat view(static_cast<int>(image.height), static_cast<int>(image.width), type,
                       const_cast<uint8_t*>(image.data.data()), image.step);
    const Pose2D robot{pose.x_m, pose.y_m, pose.theta_rad};
    const Pose2D experience{pose.experience_x_m, pose.experience_y_m, pose.experience_theta_rad};
    AnchoredProfile anchored{pose.current_experience_id, Between(experience, robot), experience, {}, {}};
    bool kept = false;  // the profile moved into the map; else `anchored` holds it, to publish
    try {
      anchored.profile = pipeline_.ProfileFromImage(view);
      if (map_.IsNewView(pose.current_experience_id, anchored.offset, config_.profile_min_spacing_m,
                         config_.profile_min_turn_rad)) {
        map_.AddProfile(std::move(anchored));
        kept = dirty_ = true;
      }
    } catch (const std::exception& e) {  // std::invalid_argument, or cv::Exception on odd input
      context_.Reject("frame", e.what());
      return;
    }
    // A pose's version says nothing of the older profiles' anchors once snapshots come: they are
    // at the last correction applied until the next one is.
    if (!rebuilt_version_) grid_map_version_ = std::max(grid_map_version_, pose.map_version);
    last_header_ = pose.header;
    context_.SetLastFrame(pose.header.frame_seq, pose.header.stamp_ns);
    profile_pub_->Publish(ProfileToMessage(pose.header, kept ? map_.profiles().back() : anchored,
                                           static_cast<float>(config_.sensor.reliable_range_m)));
    if (frames_since_rebuild_ < std::numeric_limits<int>::max() / 2) ++frames_since_rebuild_;
    if (pending_correction_ && RebuildDue()) ApplyPendingCorrection();  // the rebuild publishes the grid when done
    if (++frames_since_grid_ >= config_.grid_publish_every_n_frames) PublishGrid(pose.header, grid_map_version_);
  }

  void PublishGrid(const msg::Header& header, uint64_t map_version) {
    frames_since_grid_ = 0;
    msg::OccupancyGrid out = GridToMessage(map_.grid());
    out.header = header;
    if (out.header.robot_id.empty()) out.header.robot_id = context_.robot_id();
    out.map_version = map_version;
    grid_pub_->Publish(out);
  }

  void CountDropped() {
    const uint64_t dropped = joiner_.dropped();
    if (dropped > reported_dropped_) {
      // Each dropped image or pose counts as one rejected input.
      for (; reported_dropped_ < dropped; ++reported_dropped_)
        context_.Reject("unjoined_frame", "an image or pose whose partner frame never came was dropped");
    }
  }

  void LoadState() {
    const std::string path = context_.StateFilePath();
    if (path.empty() || context_.runtime().fresh || !std::filesystem::exists(path)) return;
    proto::OccupancyState state;
    ReadStateFile(path, kStateKind, kStateVersion, state);  // throws StateFileError when corrupt
    AnchoredProfileMap saved = AnchoredProfileMap::FromProto(state);  // validates the whole message
    // Replay into the configured grid (the saved grid parameters may differ from today's config).
    for (const AnchoredProfile& p : saved.profiles())
      map_.AddProfile(p);
    spdlog::info("loaded {} anchored profiles from {}", map_.profiles().size(), path);
  }

  void SaveState() {
    const std::string path = context_.StateFilePath();
    if (path.empty()) return;
    proto::OccupancyState state;
    {
      std::lock_guard lock(mutex_);
      if (!dirty_) return;
      state = map_.ToProto();
      dirty_ = false;
    }
    if (!WriteStateFileOrLog(path, kStateKind, kStateVersion, state)) {
      std::lock_guard lock(mutex_);
      dirty_ = true;  // try again at the next save
    }
  }

  void ExportMaps() {
    if (!config_.export_maps_on_shutdown || context_.runtime().state_dir.empty()) return;
    const std::filesystem::path dir(context_.runtime().state_dir);
    std::lock_guard lock(mutex_);
    try {
      WriteRosMap(map_.grid(), dir / "grid");
      WritePng(map_.grid(), dir / "occupancy.png");
    } catch (const std::exception& e) {
      spdlog::error("could not export the grid: {}", e.what());
    }
  }

  ServiceContext& context_;
  const Config config_;
  const ObstacleProfilePipeline pipeline_;
  std::shared_ptr<bus::Publisher<msg::ObstacleProfile>> profile_pub_;
  std::shared_ptr<bus::Publisher<msg::OccupancyGrid>> grid_pub_;

  std::mutex mutex_;
  bool stopped_ = false;
  AnchoredProfileMap map_;
  FrameJoiner<msg::Image, msg::ExperiencePose> joiner_;
  uint64_t reported_dropped_ = 0;
  // The experience-map version the grid reflects: the newest snapshot applied (rebuilt, or found to
  // move no anchor); before the first snapshot, the newest pose's.
  uint64_t grid_map_version_ = 0;
  std::optional<uint64_t> rebuilt_version_;
  struct PendingCorrection {
    uint64_t map_version = 0;
    std::unordered_map<uint64_t, Pose2D> poses;
  };
  std::optional<PendingCorrection> pending_correction_;
  struct PlannedRebuild {
    PlannedRebuild(AnchoredProfileMap::RebuildPlan p, uint64_t version) : plan(std::move(p)), map_version(version) {}
    AnchoredProfileMap::RebuildPlan plan;
    uint64_t map_version = 0;
    std::stop_source stop;  // requested when a newer map waits at the stop
  };
  std::optional<PlannedRebuild> planned_rebuild_;  // set from the plan until the rebuild thread adopts it
  bool grid_behind_anchors_ = false;  // a plan moved the anchors and its grid is not adopted (yet, or dropped)
  bool stop_rebuilds_ = false;
  std::condition_variable rebuild_wake_;
  std::thread rebuild_thread_;  // started by the first rebuild, joined by StopRebuilds
  int frames_since_rebuild_ = std::numeric_limits<int>::max() / 2;
  std::chrono::steady_clock::time_point rebuild_not_before_;  // rebuild_max_busy_share after the last rebuild
  msg::Header last_header_;
  int frames_since_grid_ = 0;
  bool dirty_ = true;  // a fresh start saves (an empty map) too, so a restart sees the file
  std::chrono::steady_clock::time_point last_save_;
};

OccupancyNode::OccupancyNode(ServiceContext& context, const Config& config)
    : mapper_(std::make_shared<Mapper>(context, config)) {
  subscriptions_ = Mapper::Subscribe(mapper_);
}

OccupancyNode::~OccupancyNode() {
  subscriptions_.clear();  // no callback runs after this
  mapper_->Stop();
}

void OccupancyNode::Tick() { mapper_->Tick(); }

}  // namespace rslam::occupancy
