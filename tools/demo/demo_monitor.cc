#include "tools/demo/demo_monitor.h"

namespace rslam::demo {

DemoMonitor::DemoMonitor(bus::Participant& participant, const std::string& robot_id) {
  namespace t = bus::topics;
  auto add = [&](auto topic, auto callback, std::string partition) {
    using T = typename decltype(topic)::Type;
    subscriptions_.push_back(std::make_shared<bus::Subscriber<T>>(
        participant, topic, std::function<void(const T&)>(std::move(callback)), std::move(partition)));
  };
  add(
      t::kGroundTruth,
      [this](const msg::GroundTruthPose& m) {
        std::lock_guard lock(mutex_);
        seen_.ground_truth.push_back({m.header.frame_seq, m.header.stamp_ns, m.x_m, m.y_m, m.theta_rad});
        progress_.frames = std::max<uint64_t>(progress_.frames, m.header.frame_seq + 1);
      },
      robot_id);
  add(
      t::kExperienceMapPose,
      [this](const msg::ExperiencePose& m) {
        std::lock_guard lock(mutex_);
        seen_.experience_poses.push_back({m.header.frame_seq, m.header.stamp_ns, m.x_m, m.y_m, m.theta_rad});
        seen_.experience_first_frame.emplace(m.current_experience_id, m.header.frame_seq);
        seen_.experience_count = progress_.experience_count = m.experience_count;
        seen_.link_count = progress_.link_count = m.link_count;
      },
      robot_id);
  add(
      t::kOdometryVelocity,
      [this](const msg::Velocity& m) {
        std::lock_guard lock(mutex_);
        seen_.odometry.push_back({m.header.frame_seq, m.header.stamp_ns, m.vtrans_mps, m.vrot_radps, m.dt_s});
      },
      robot_id);
  add(
      t::kTemplatesView,
      [this](const msg::ViewTemplate& m) {
        std::lock_guard lock(mutex_);
        seen_.template_count = progress_.template_count = std::max(seen_.template_count, m.template_count);
      },
      robot_id);
  add(
      t::kExperienceMapMap,
      [this](const msg::ExperienceMap& m) {
        std::lock_guard lock(mutex_);
        seen_.map = m;
      },
      robot_id);
  add(
      t::kOccupancyGrid,
      [this](const msg::OccupancyGrid& m) {
        std::lock_guard lock(mutex_);
        seen_.grid = m;
        ++progress_.grid_version;
      },
      robot_id);
  add(
      t::kExplorerStatus,
      [this](const msg::ExplorerStatus& m) {
        std::lock_guard lock(mutex_);
        seen_.explorer = m;
        progress_.explorer_state = m.state;
      },
      robot_id);
  add(
      t::kStatus,
      [this](const msg::ServiceStatus& m) {
        std::lock_guard lock(mutex_);
        seen_.services[m.service] = m;
      },
      bus::kAllRobots);
}

DemoMonitor::~DemoMonitor() {
  // Subscriber threads call back into this object: stop them before the members go.
  subscriptions_.clear();
}

DemoObservations DemoMonitor::Snapshot() const {
  std::lock_guard lock(mutex_);
  return seen_;
}

DemoProgress DemoMonitor::Progress() const {
  std::lock_guard lock(mutex_);
  return progress_;
}

std::optional<msg::OccupancyGrid> DemoMonitor::LatestGrid() const {
  std::lock_guard lock(mutex_);
  return seen_.grid;
}

}  // namespace rslam::demo
