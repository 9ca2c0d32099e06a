// rslam-pose-cells and rslam-experience-map together as processes on a scripted drive (three
// laps of a square, odometry and views published at a steady pace), one of them killed with
// SIGKILL mid-run and started again. The map must stay consistent: no id mismatch, nothing
// applied twice, and the same map as an uninterrupted run when nothing was lost.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "tests/support/child_process.h"
#include "tests/integration/pose_cells/scripted_actions.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::ScratchFolder;
using testing::WaitFor;

const std::string kPoseCells = RSLAM_BINARY_DIR "/bin/rslam-pose-cells";
const std::string kExperienceMap = RSLAM_BINARY_DIR "/bin/rslam-experience-map";
constexpr int kFrames = 3 * testing::kLapFrames;
constexpr int kKillMapAtFrame = 130;        // lap 2: loop closures being applied
constexpr int kKillPoseCellsAtFrame = 85;   // late in lap 1: experiences being created

class BackendRestartTest : public ::testing::Test {
 protected:
  BackendRestartTest() : script_(testing::ScriptedLoop(kFrames)) {
    bus::BusConfig config;
    config.ApplyEnvironment();  // RSLAM_DDS picks the vendor of the test and the services alike
    config.domain_id = domain_.id();
    participant_ = bus::Participant::Create(config);
    velocity_pub_ = std::make_unique<bus::Publisher<msg::Velocity>>(*participant_, bus::topics::kOdometryVelocity);
    view_pub_ = std::make_unique<bus::Publisher<msg::ViewTemplate>>(*participant_, bus::topics::kTemplatesView);
    map_sub_ = std::make_unique<bus::Subscriber<msg::ExperienceMap>>(*participant_, bus::topics::kExperienceMapMap);
    status_sub_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(
        *participant_, bus::topics::kStatus, [this](const msg::ServiceStatus& s) {
          if (s.service == "experience_map") {
            map_rejected_ = std::max<uint64_t>(map_rejected_, s.messages_rejected);
            map_status_seen_ = true;
          }
          if (s.service == "pose_cells") pose_cells_status_seen_ = true;
        });
    action_sub_ = std::make_unique<bus::Subscriber<msg::PoseCellAction>>(
        *participant_, bus::topics::kPoseCellsAction, [this](const msg::PoseCellAction& a) {
          last_action_seq_ = std::max<int64_t>(last_action_seq_, static_cast<int64_t>(a.action_seq));
          ++actions_seen_;
        });
  }

  ~BackendRestartTest() override {
    stop_publishing_ = true;
    if (publisher_.joinable()) publisher_.join();
  }

  std::vector<std::string> CommonArgs() const {
    return {"--domain", std::to_string(domain_.id()), "--state-dir", state_dir_.path().string(),
            "--set", "service.heartbeat_period_s=0.1", "--set", "service.state_save_period_s=0.1"};
  }

  std::unique_ptr<ChildProcess> StartPoseCells(double resync_timeout_s) {
    auto args = CommonArgs();
    args.insert(args.end(), {"--set", "pose_cells.resync_timeout_s=" + std::to_string(resync_timeout_s)});
    pose_cells_status_seen_ = false;
    auto p = std::make_unique<ChildProcess>(kPoseCells, args);
    // Its heartbeat comes after its subscriptions exist and its resynchronisation is done.
    EXPECT_TRUE(WaitFor([&] { return pose_cells_status_seen_.load() && velocity_pub_->MatchedSubscribers() > 0 &&
                                       view_pub_->MatchedSubscribers() > 0; },
                          15s))
        << "status seen " << pose_cells_status_seen_ << ", odometry readers " << velocity_pub_->MatchedSubscribers()
        << ", view readers " << view_pub_->MatchedSubscribers() << "\n"
        << p->Output();
    return p;
  }

  std::unique_ptr<ChildProcess> StartExperienceMap() {
    map_status_seen_ = false;
    auto p = std::make_unique<ChildProcess>(kExperienceMap, CommonArgs());
    EXPECT_TRUE(WaitFor([&] { return map_status_seen_.load() && map_sub_->MatchedPublishers() > 0; }, 15s))
        << p->Output();
    return p;
  }

  // Publishes the script at a steady pace on a thread of its own: the drive goes on whatever
  // happens to the services.
  void StartDrive(std::chrono::milliseconds period) {
    publisher_ = std::thread([this, period] {
      auto next = std::chrono::steady_clock::now();
      for (int i = 0; i < kFrames && !stop_publishing_; ++i) {
        try {
          velocity_pub_->Publish(script_[i].velocity);
          view_pub_->Publish(script_[i].view);
        } catch (const bus::BusError&) {
          // A killed reader stays matched until its lease expires and a reliable writer can
          // block on it; the drive goes on (that frame is lost, as for a real producer).
          ++failed_writes_;
        }
        published_ = i + 1;
        next += period;
        std::this_thread::sleep_until(next);
      }
    });
  }

  void AwaitDriveEnd() {
    if (publisher_.joinable()) publisher_.join();
  }

  // The snapshot once the map has applied the last action the pose cells published.
  std::optional<msg::ExperienceMap> AwaitFinalMap() {
    // Actions stop coming once the pose cells have processed the last frame.
    int64_t seen = -1;
    WaitFor(
        [&] {
          const int64_t now = last_action_seq_;
          const bool quiet = now == seen;
          seen = now;
          if (!quiet) std::this_thread::sleep_for(300ms);
          return quiet;
        },
        15s);
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto m = map_sub_->TakeOne(100ms); m && static_cast<int64_t>(m->action_seq) == last_action_seq_) return m;
    }
    return std::nullopt;
  }

  testing::TestDomain domain_;
  ScratchFolder state_dir_;
  const std::vector<testing::ScriptedFrame> script_;
  std::unique_ptr<bus::Participant> participant_;
  std::unique_ptr<bus::Publisher<msg::Velocity>> velocity_pub_;
  std::unique_ptr<bus::Publisher<msg::ViewTemplate>> view_pub_;
  std::unique_ptr<bus::Subscriber<msg::ExperienceMap>> map_sub_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> status_sub_;
  std::unique_ptr<bus::Subscriber<msg::PoseCellAction>> action_sub_;
  std::atomic<uint64_t> map_rejected_{0};
  std::atomic<bool> map_status_seen_{false}, pose_cells_status_seen_{false};
  std::atomic<int64_t> last_action_seq_{-1};
  std::atomic<uint64_t> actions_seen_{0};
  std::atomic<int> published_{0};
  std::atomic<int> failed_writes_{0};
  std::atomic<bool> stop_publishing_{false};
  std::thread publisher_;
};

TEST_F(BackendRestartTest, ExperienceMapRestartAfterSigkillEndsWithTheUninterruptedMap) {
  auto map = StartExperienceMap();
  auto pose_cells = StartPoseCells(0.3);
  StartDrive(10ms);
  const auto state_file = state_dir_.path() / "experience_map.pb";
  ASSERT_TRUE(WaitFor([&] { return published_ >= kKillMapAtFrame && std::filesystem::exists(state_file); }, 15s));
  map->Signal(SIGKILL);
  ASSERT_TRUE(map->WaitExit(5s));
  map = StartExperienceMap();  // reloads its state; the missed actions come from the pose cells' log
  AwaitDriveEnd();
  const auto final_map = AwaitFinalMap();
  ASSERT_TRUE(final_map) << map->Output() << pose_cells->Output();
  EXPECT_NE(map->Output().find("loaded"), std::string::npos) << map->Output();

  // Nothing was lost (the pose cells saw every frame): the map is the uninterrupted one.
  ASSERT_EQ(last_action_seq_, kFrames - 1);
  const testing::ReferenceMap reference = testing::ApplyAll(testing::ScriptedActions(script_));
  ASSERT_GE(reference.loop_closures, 1u);
  ASSERT_EQ(final_map->experiences.size(), reference.experiences);
  ASSERT_EQ(final_map->links.size(), reference.links.size());
  size_t closures = 0;
  for (size_t i = 0; i < reference.links.size(); ++i) {
    EXPECT_EQ(std::make_pair(final_map->links[i].from_id, final_map->links[i].to_id), reference.links[i]) << i;
    closures += final_map->links[i].closes_loop;
  }
  EXPECT_EQ(closures, reference.loop_closures);
  for (size_t i = 0; i < reference.experiences; ++i) {
    EXPECT_NEAR(final_map->experiences[i].x_m, reference.positions[i].first, 1e-6) << i;
    EXPECT_NEAR(final_map->experiences[i].y_m, reference.positions[i].second, 1e-6) << i;
  }
  EXPECT_EQ(map_rejected_, 0u) << map->Output();
  EXPECT_TRUE(pose_cells->Running());
}

TEST_F(BackendRestartTest, PoseCellsRestartAfterSigkillResyncsFromTheMapWithoutIdMismatch) {
  auto map = StartExperienceMap();
  auto pose_cells = StartPoseCells(0.3);
  // 50 frames/s: the frames lost while the pose cells restart (lost distance, so a few extra
  // experiences) stay a small part of the drive.
  StartDrive(20ms);
  const auto state_file = state_dir_.path() / "pose_cells.pb";
  ASSERT_TRUE(WaitFor([&] { return published_ >= kKillPoseCellsAtFrame && std::filesystem::exists(state_file); }, 15s));
  pose_cells->Signal(SIGKILL);
  ASSERT_TRUE(pose_cells->WaitExit(5s));
  const int64_t seq_at_kill = last_action_seq_;
  pose_cells = StartPoseCells(3.0);  // frames published meanwhile are lost for it
  AwaitDriveEnd();
  const auto final_map = AwaitFinalMap();
  ASSERT_TRUE(final_map) << map->Output() << pose_cells->Output();
  EXPECT_NE(pose_cells->Output().find("loaded"), std::string::npos) << pose_cells->Output();

  // The restarted pose cells continued the map's sequence and ids: nothing refused.
  EXPECT_GT(last_action_seq_, seq_at_kill);
  EXPECT_EQ(map_rejected_, 0u) << map->Output() << pose_cells->Output();
  const testing::ReferenceMap reference = testing::ApplyAll(testing::ScriptedActions(script_));
  const double count = static_cast<double>(final_map->experiences.size());
  RecordProperty("experiences", static_cast<int>(final_map->experiences.size()));
  RecordProperty("uninterrupted_experiences", static_cast<int>(reference.experiences));
  RecordProperty("actions_lost_frames", kFrames - 1 - static_cast<int>(last_action_seq_));
  EXPECT_NEAR(count, static_cast<double>(reference.experiences), 0.05 * reference.experiences)
      << pose_cells->Output();
  for (size_t i = 0; i < final_map->experiences.size(); ++i) EXPECT_EQ(final_map->experiences[i].id, i);
  EXPECT_TRUE(map->Running());
  if (std::getenv("RSLAM_TEST_VERBOSE")) std::cout << pose_cells->Output() << map->Output();
}

}  // namespace
}  // namespace rslam
