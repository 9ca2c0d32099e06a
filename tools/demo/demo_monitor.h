#pragma once
// What `rslam demo` sees on the bus while the demo runs: ground truth and the pipeline's per-frame
// outputs (for the trajectory errors), the latest experience map, occupancy grid and explorer
// status (for the metrics and the progress line), and every service's heartbeat. Subscriber
// callbacks only append under a mutex, so the monitor never slows the pipeline down.

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/subscriber.h"

namespace rslam::demo {

struct FramePose {
  uint64_t frame_seq = 0;
  int64_t stamp_ns = 0;
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;
};

struct FrameVelocity {
  uint64_t frame_seq = 0;
  int64_t stamp_ns = 0;
  double vtrans_mps = 0.0;
  double vrot_radps = 0.0;
  double dt_s = 0.0;
};

// A consistent copy of everything seen so far.
struct DemoObservations {
  std::vector<FramePose> ground_truth;          // sim/ground_truth, arrival order
  std::vector<FramePose> experience_poses;      // experience_map/pose (map frame)
  std::vector<FrameVelocity> odometry;          // odometry/velocity
  std::map<uint32_t, uint64_t> experience_first_frame;  // frame at which an experience was first current
  std::optional<msg::ExperienceMap> map;        // latest experience_map/map
  std::optional<msg::OccupancyGrid> grid;       // latest occupancy/grid
  std::optional<msg::ExplorerStatus> explorer;  // latest explorer/status
  uint32_t template_count = 0;                  // from templates/view
  uint32_t experience_count = 0;                // from experience_map/pose
  uint32_t link_count = 0;
  std::map<std::string, msg::ServiceStatus> services;  // latest heartbeat per service
};

// The small part the progress line needs, cheap to read often.
struct DemoProgress {
  uint64_t frames = 0;  // frames of ground truth seen
  uint32_t template_count = 0;
  uint32_t experience_count = 0;
  uint32_t link_count = 0;
  std::optional<msg::ExplorationState> explorer_state;
  uint64_t grid_version = 0;  // increments with every grid received
};

class DemoMonitor {
 public:
  // Subscribes the robot's topics (and every robot's heartbeats) through participant, which
  // must outlive this.
  DemoMonitor(bus::Participant& participant, const std::string& robot_id);
  DemoMonitor(const DemoMonitor&) = delete;
  DemoMonitor& operator=(const DemoMonitor&) = delete;
  ~DemoMonitor();

  DemoObservations Snapshot() const;
  DemoProgress Progress() const;
  std::optional<msg::OccupancyGrid> LatestGrid() const;

 private:
  mutable std::mutex mutex_;
  DemoObservations seen_;
  DemoProgress progress_;
  std::vector<std::shared_ptr<void>> subscriptions_;
};

}  // namespace rslam::demo
