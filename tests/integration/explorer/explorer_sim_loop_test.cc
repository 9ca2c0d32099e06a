// The exploration loop closed through the simulator: rslam-sim (camera + body), rslam-occupancy
// and rslam-explorer as processes, with the test standing in for the SLAM core: it forwards
// sim/camera to camera/image and turns the simulator's ground truth into experience_map/pose
// (one experience at the start pose, the map frame = the start pose). One config file for every
// process, as in the demo: the services' defaults must match the simulator's camera and floor.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::ScratchFolder;

constexpr double kResolution = 0.05;
constexpr int kWidth = 60;   // 3 m
constexpr int kHeight = 40;  // 2 m
constexpr double kStartX = 1.5, kStartY = 1.0;

// A 3 m x 2 m room (map_server PGM: 254 free, 0 wall) with a one-cell wall all round.
std::string WriteRoom(const std::filesystem::path& dir) {
  {
    std::ofstream pgm(dir / "room.pgm", std::ios::binary);
    pgm << "P5\n" << kWidth << " " << kHeight << "\n255\n";
    for (int row = 0; row < kHeight; ++row)
      for (int x = 0; x < kWidth; ++x)
        pgm.put(static_cast<char>(row == 0 || x == 0 || row == kHeight - 1 || x == kWidth - 1 ? 0 : 254));
  }
  std::ofstream yaml(dir / "room.yaml");
  yaml << "image: room.pgm\nresolution: " << kResolution << "\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
       << "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
  return (dir / "room.yaml").string();
}

TEST(ExplorerSimLoopTest, ExploresASimulatedRoomToCompletion) {
  testing::TestDomain domain;
  ScratchFolder dir;
  const std::string world = WriteRoom(dir.path());
  const auto config = dir.path() / "demo.yaml";
  {
    std::ofstream out(config);
    out << "sim:\n  world_yaml: " << world << "\n  start_pose: [" << kStartX << ", " << kStartY << ", 0.0]\n"
        << "  max_frames: 6000\n"
        // The sim's lockstep readers may match after the first frames' reports went out; it then
        // waits startup_timeout_s before going on without them (15 s by default).
        << "  startup_timeout_s: 3\n"
        << "service:\n  heartbeat_period_s: 0.5\n";
  }

  bus::BusConfig bus_config;
  bus_config.domain_id = domain.id();
  auto participant = bus::Participant::Create(bus_config);
  bus::Publisher<msg::Image> image_pub(*participant, bus::topics::kCameraImage);
  bus::Publisher<msg::ExperiencePose> pose_pub(*participant, bus::topics::kExperienceMapPose);
  bus::Subscriber<msg::ExplorerStatus> status_sub(*participant, bus::topics::kExplorerStatus);
  bus::Subscriber<msg::OccupancyGrid> grid_sub(*participant, bus::topics::kOccupancyGrid);
  // The SLAM core's stand-in. Callbacks run on subscriber threads.
  bus::Subscriber<msg::Image> camera_sub(*participant, bus::topics::kSimCamera,
                                         [&](const msg::Image& image) { image_pub.Publish(image); });
  bus::Subscriber<msg::GroundTruthPose> truth_sub(
      *participant, bus::topics::kGroundTruth, [&](const msg::GroundTruthPose& truth) {
        const double dx = truth.x_m - kStartX, dy = truth.y_m - kStartY;
        msg::ExperiencePose pose;
        pose.header = truth.header;
        pose.current_experience_id = 0;
        pose.x_m = dx;  // the start heading is 0: the map frame is the world shifted
        pose.y_m = dy;
        pose.theta_rad = truth.theta_rad;
        pose.experience_count = 1;
        pose.map_version = 1;
        pose_pub.Publish(pose);
      });

  const std::vector<std::string> common{"--config", config.string(), "--domain", std::to_string(domain.id()),
                                        "--fresh"};
  const std::string bin = RSLAM_BINARY_DIR "/bin/";
  ChildProcess occupancy(bin + "rslam-occupancy", common);
  ChildProcess explorer(bin + "rslam-explorer", common);
  ASSERT_TRUE(testing::WaitFor([&] { return image_pub.MatchedSubscribers() >= 1 && pose_pub.MatchedSubscribers() >= 2; },
                                 10s));
  ChildProcess sim(bin + "rslam-sim", common);

  std::optional<msg::ExplorerStatus> last;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (auto s = status_sub.TakeOne(200ms)) {
      last = s;
      if (s->state == msg::ExplorationState::EXPLORATION_COMPLETE) break;
    }
    if (!sim.Running() || !occupancy.Running() || !explorer.Running()) break;
  }
  ASSERT_TRUE(last) << explorer.Output();
  ASSERT_EQ(last->state, msg::ExplorationState::EXPLORATION_COMPLETE)
      << "reason: " << last->reason << "\n--- explorer\n" << explorer.Output() << "\n--- occupancy\n"
      << occupancy.Output() << "\n--- sim\n" << sim.Output();
  EXPECT_GE(last->commands_sent, 2u);

  // The grid the exploration ended with shows most of the room as free floor. Stop the frames
  // first: the mapper publishes a grid every few frames for as long as they come.
  sim.Signal(SIGTERM);
  EXPECT_EQ(sim.WaitExit(10s), 0) << sim.Output();
  std::optional<msg::OccupancyGrid> grid;
  while (auto g = grid_sub.TakeOne(500ms)) grid = g;
  ASSERT_TRUE(grid);
  int inside = 0, free = 0;
  for (double y = 0.3; y <= kHeight * kResolution - 0.3; y += 0.05) {
    for (double x = 0.3; x <= kWidth * kResolution - 0.3; x += 0.05) {
      const int cx = static_cast<int>(std::floor((x - kStartX - grid->origin_x_m) / grid->resolution_m));
      const int cy = static_cast<int>(std::floor((y - kStartY - grid->origin_y_m) / grid->resolution_m));
      const int8_t v = grid->cells.at(static_cast<size_t>(cy) * grid->width + cx);
      ++inside;
      if (v >= 0 && v <= 19) ++free;
    }
  }
  EXPECT_GE(free, inside * 6 / 10) << free << " of " << inside << " room cells free";
  std::cout << "explored: " << last->commands_sent << " commands, " << last->goals_set_aside
            << " goals set aside, " << free << " of " << inside << " room cells free (" << last->reason << ")\n";
}

}  // namespace
}  // namespace rslam
