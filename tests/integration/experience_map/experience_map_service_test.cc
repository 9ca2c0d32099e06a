// rslam-experience-map as a process on the test's own DDS domain: pose-cell actions in, the
// robot's pose per action and map snapshots out.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
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

const std::string kBinary = RSLAM_BINARY_DIR "/bin/rslam-experience-map";

msg::PoseCellAction Action(uint64_t seq, msg::ActionKind kind, uint32_t id, uint32_t from) {
  msg::PoseCellAction a;
  a.header = testing::ScriptedHeader(seq);
  a.action_seq = seq;
  a.kind = kind;
  a.experience_id = id;
  a.from_experience_id = from;
  a.vtrans_mps = 1.0;
  a.dt_s = 0.1;
  return a;
}

constexpr uint32_t kNone = 0xffffffffu;

class ExperienceMapServiceTest : public ::testing::Test {
 protected:
  ExperienceMapServiceTest() {
    bus::BusConfig config;
    config.ApplyEnvironment();  // RSLAM_DDS picks the vendor of the test and the services alike
    config.domain_id = domain_.id();
    participant_ = bus::Participant::Create(config);
    action_pub_ = std::make_unique<bus::Publisher<msg::PoseCellAction>>(*participant_, bus::topics::kPoseCellsAction);
    pose_sub_ = std::make_unique<bus::Subscriber<msg::ExperiencePose>>(*participant_, bus::topics::kExperienceMapPose);
    map_sub_ = std::make_unique<bus::Subscriber<msg::ExperienceMap>>(*participant_, bus::topics::kExperienceMapMap);
    status_sub_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(*participant_, bus::topics::kStatus);
  }

  std::unique_ptr<ChildProcess> Start(std::vector<std::string> extra = {}) {
    std::vector<std::string> args{"--domain", std::to_string(domain_.id()), "--state-dir", state_dir_.path().string(),
                                  "--set", "service.heartbeat_period_s=0.2"};
    args.insert(args.end(), extra.begin(), extra.end());
    auto process = std::make_unique<ChildProcess>(kBinary, args);
    const bool matched = WaitFor(
        [&] { return pose_sub_->MatchedPublishers() > 0 && map_sub_->MatchedPublishers() > 0; }, 10s);
    EXPECT_TRUE(matched) << process->Output();
    return process;
  }

  std::vector<msg::ExperiencePose> AwaitPoses(size_t n, std::chrono::milliseconds timeout = 10s) {
    std::vector<msg::ExperiencePose> out;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (out.size() < n && std::chrono::steady_clock::now() < deadline) {
      if (auto p = pose_sub_->TakeOne(100ms)) out.push_back(*p);
    }
    return out;
  }

  std::optional<msg::ExperienceMap> AwaitMap(const std::function<bool(const msg::ExperienceMap&)>& pred,
                                             std::chrono::milliseconds timeout = 10s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto m = map_sub_->TakeOne(100ms); m && pred(*m)) return m;
    }
    return std::nullopt;
  }

  static constexpr uint64_t kWallFrames = 60;
  std::vector<msg::ExperiencePose> DriveStraightPastWalls() {
    for (uint64_t seq = 0; seq < kWallFrames; ++seq) {
      msg::PoseCellAction a = seq == 0 ? Action(0, msg::ActionKind::ACTION_CREATE, 0, kNone)
                                       : Action(seq, msg::ActionKind::ACTION_NONE, kNone, kNone);
      a.vrot_radps = 0.2;  // 20 mrad a frame of 0.1 s
      a.wall_seen = true;
      a.wall_direction_rad = seq == 30 ? std::nan("") : -0.2;  // in the robot frame
      action_pub_->Publish(a);
    }
    return AwaitPoses(kWallFrames - 1);  // the malformed one publishes nothing
  }

  // The first heartbeat of the service that satisfies `done`.
  template <class Done>
  std::optional<msg::ServiceStatus> AwaitStatus(Done done, std::chrono::milliseconds timeout = 5s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto s = status_sub_->TakeOne(100ms); s && s->service == "experience_map" && done(*s)) return s;
    }
    return std::nullopt;
  }
  std::optional<msg::ServiceStatus> AwaitRejected(uint64_t min_rejected) {
    return AwaitStatus([&](const msg::ServiceStatus& s) { return s.messages_rejected >= min_rejected; });
  }

  testing::TestDomain domain_;
  ScratchFolder state_dir_;
  std::unique_ptr<bus::Participant> participant_;
  std::unique_ptr<bus::Publisher<msg::PoseCellAction>> action_pub_;
  std::unique_ptr<bus::Subscriber<msg::ExperiencePose>> pose_sub_;
  std::unique_ptr<bus::Subscriber<msg::ExperienceMap>> map_sub_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> status_sub_;
};

TEST_F(ExperienceMapServiceTest, AppliesOutOfOrderAndDuplicatedActionsInSequenceOrder) {
  auto service = Start();
  const auto actions = testing::ScriptedActions(testing::ScriptedLoop(testing::kLapFrames + 20));
  const testing::ReferenceMap reference = testing::ApplyAll(actions);
  ASSERT_GE(reference.loop_closures, 1u);
  // Neighbours swapped, every tenth action sent twice, and the first ten again at the end.
  std::vector<msg::PoseCellAction> sent;
  for (size_t i = 0; i + 1 < actions.size(); i += 2) {
    sent.push_back(actions[i + 1]);
    sent.push_back(actions[i]);
    if (i % 10 == 0) sent.push_back(actions[i]);
  }
  if (actions.size() % 2) sent.push_back(actions.back());
  for (size_t i = 0; i < 10; ++i) sent.push_back(actions[i]);
  for (const auto& a : sent) action_pub_->Publish(a);

  const auto poses = AwaitPoses(actions.size());
  ASSERT_EQ(poses.size(), actions.size()) << service->Output();
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(poses[i].action_seq, i);
    EXPECT_EQ(poses[i].header, actions[i].header);
  }
  EXPECT_FALSE(pose_sub_->TakeOne(300ms)) << "a duplicate was applied";
  EXPECT_EQ(poses.back().experience_count, reference.experiences);
  EXPECT_EQ(poses.back().link_count, reference.links.size());

  const auto map = AwaitMap([&](const msg::ExperienceMap& m) { return m.action_seq == actions.size() - 1; });
  ASSERT_TRUE(map) << service->Output();
  ASSERT_EQ(map->experiences.size(), reference.experiences);
  ASSERT_EQ(map->links.size(), reference.links.size());
  size_t closures = 0;
  for (size_t i = 0; i < map->links.size(); ++i) {
    EXPECT_EQ(std::make_pair(map->links[i].from_id, map->links[i].to_id), reference.links[i]);
    closures += map->links[i].closes_loop;
  }
  EXPECT_EQ(closures, reference.loop_closures);
  for (size_t i = 0; i < map->experiences.size(); ++i) {
    EXPECT_EQ(map->experiences[i].id, i);
    EXPECT_NEAR(map->experiences[i].x_m, reference.positions[i].first, 1e-9);
    EXPECT_NEAR(map->experiences[i].y_m, reference.positions[i].second, 1e-9);
  }
  EXPECT_EQ(map->current_experience_id, poses.back().current_experience_id);
  // The pose of the current experience travels with every pose message.
  const auto& current = map->experiences[map->current_experience_id];
  EXPECT_NEAR(poses.back().experience_x_m, current.x_m, 1e-6);
  EXPECT_TRUE(service->Running());
}

TEST_F(ExperienceMapServiceTest, ActionWithUnknownIdIsRejectedAndTheServiceKeepsRunning) {
  auto service = Start();
  action_pub_->Publish(Action(0, msg::ActionKind::ACTION_CREATE, 0, kNone));
  action_pub_->Publish(Action(1, msg::ActionKind::ACTION_LINK, 99, 0));  // no experience 99
  action_pub_->Publish(Action(2, msg::ActionKind::ACTION_CREATE, 1, 0));
  msg::PoseCellAction bad = Action(3, msg::ActionKind::ACTION_NONE, kNone, kNone);
  bad.dt_s = std::nan("");
  action_pub_->Publish(bad);
  action_pub_->Publish(Action(4, msg::ActionKind::ACTION_NONE, kNone, kNone));
  const auto poses = AwaitPoses(4);  // the malformed one publishes nothing
  ASSERT_EQ(poses.size(), 4u) << service->Output();
  EXPECT_EQ(poses[1].action_seq, 1u);
  EXPECT_EQ(poses[1].experience_count, 1u);  // the link was not applied
  EXPECT_EQ(poses[2].experience_count, 2u);
  EXPECT_EQ(poses[3].action_seq, 4u);
  const auto status = AwaitRejected(2);
  ASSERT_TRUE(status) << service->Output();
  EXPECT_TRUE(service->Running());
}

// The robot drives straight past walls at 0.2 rad to it while its odometry turns 20 mrad a frame
// it does not turn; one action's wall direction is not finite (refused: nothing of it applied).
TEST_F(ExperienceMapServiceTest, WallDirectionsInTheActionsHoldTheHeadingWithExpManhattan) {
  auto service = Start({"--set", "experience_map.exp_initial_em_deg=0", "--set", "experience_map.exp_manhattan=true",
                        "--set", "experience_map.exp_manhattan_reference_frames=3"});
  const auto poses = DriveStraightPastWalls();
  ASSERT_EQ(poses.size(), kWallFrames - 1) << service->Output();
  // Axes fixed after 3 frames (40 mrad of drift on average), then held where a frame's drift is
  // a fifth of the offset: 40 + 100 - 20 mrad.
  EXPECT_NEAR(poses.back().theta_rad, 0.12, 1e-6);
  ASSERT_TRUE(AwaitRejected(1)) << service->Output();
  EXPECT_TRUE(service->Running());
}

// Experience 0 recognised 6 m from where the map has the robot: refused (no link, the robot
// stays); the pose cells, now at 0, create the next experience from it, which the service takes.
TEST_F(ExperienceMapServiceTest, ARecognitionFarFromTheMapsRobotIsRefusedAndTheNextCreateTaken) {
  auto service = Start({"--set", "experience_map.exp_initial_em_deg=0", "--set",
                        "experience_map.exp_recognition_max_jump_m=1"});
  uint64_t seq = 0;
  action_pub_->Publish(Action(seq++, msg::ActionKind::ACTION_CREATE, 0, kNone));
  while (seq < 30) action_pub_->Publish(Action(seq++, msg::ActionKind::ACTION_NONE, kNone, kNone));
  action_pub_->Publish(Action(seq++, msg::ActionKind::ACTION_CREATE, 1, 0));
  while (seq < 60) action_pub_->Publish(Action(seq++, msg::ActionKind::ACTION_NONE, kNone, kNone));
  action_pub_->Publish(Action(seq++, msg::ActionKind::ACTION_LINK, 0, 1));
  action_pub_->Publish(Action(seq++, msg::ActionKind::ACTION_CREATE, 2, 0));
  const auto poses = AwaitPoses(seq);
  ASSERT_EQ(poses.size(), seq) << service->Output();
  const msg::ExperiencePose& refused = poses[seq - 2];
  EXPECT_EQ(refused.current_experience_id, 1u);
  EXPECT_NEAR(refused.x_m, 6.1, 1e-6);
  EXPECT_EQ(refused.link_count, 1u);
  const msg::ExperiencePose& created = poses[seq - 1];
  EXPECT_EQ(created.current_experience_id, 2u);
  EXPECT_EQ(created.experience_count, 3u);
  EXPECT_EQ(created.link_count, 2u);  // 0 -> 1, 1 -> 2
  EXPECT_NEAR(created.x_m, 6.2, 1e-6);
  // A heartbeat once every action has been taken in.
  const auto status = AwaitStatus([&](const msg::ServiceStatus& s) { return s.messages_in >= seq; });
  ASSERT_TRUE(status) << service->Output();
  EXPECT_EQ(status->messages_rejected, 0u) << service->Output();
  // The log names the gate and both figures: experience 0 (laid at 0.1 m) 6 m behind, 1 m allowed.
  EXPECT_NE(service->Output().find("recognition of experience 0 refused: it would move the robot 6.00 m from where "
                                   "the map has it (exp_recognition_max_jump_m + _jump_per_m, at most _jump_cap_m: 1.00 m here)"),
            std::string::npos)
      << service->Output();
}

TEST_F(ExperienceMapServiceTest, WallDirectionsChangeNothingWithoutExpManhattan) {
  auto service = Start({"--set", "experience_map.exp_initial_em_deg=0"});
  const auto poses = DriveStraightPastWalls();
  ASSERT_EQ(poses.size(), kWallFrames - 1) << service->Output();
  EXPECT_NEAR(poses.back().theta_rad, 0.02 * (kWallFrames - 1), 1e-9);
}

TEST_F(ExperienceMapServiceTest, MissingActionIsSkippedAfterTheGapWindow) {
  auto service = Start({"--set", "experience_map.gap_window_actions=5"});
  action_pub_->Publish(Action(0, msg::ActionKind::ACTION_CREATE, 0, kNone));
  for (uint64_t seq = 2; seq <= 8; ++seq) action_pub_->Publish(Action(seq, msg::ActionKind::ACTION_NONE, kNone, kNone));
  const auto poses = AwaitPoses(8);
  ASSERT_EQ(poses.size(), 8u) << service->Output();
  EXPECT_EQ(poses[0].action_seq, 0u);
  for (size_t i = 1; i < poses.size(); ++i) EXPECT_EQ(poses[i].action_seq, i + 1);
  ASSERT_TRUE(AwaitRejected(1)) << service->Output();
  action_pub_->Publish(Action(1, msg::ActionKind::ACTION_CREATE, 1, 0));  // too late: ignored
  EXPECT_FALSE(pose_sub_->TakeOne(300ms));
}

TEST_F(ExperienceMapServiceTest, SavedMapFileLoadsIntoANewServiceAndItsSnapshot) {
  const std::string map_file = (state_dir_.path() / "saved_map.pb").string();
  const auto actions = testing::ScriptedActions(testing::ScriptedLoop(testing::kLapFrames + 5));
  const testing::ReferenceMap reference = testing::ApplyAll(actions);
  {
    auto service = Start({"--set", "experience_map.save_map=" + map_file});
    for (const auto& a : actions) action_pub_->Publish(a);
    ASSERT_EQ(AwaitPoses(actions.size()).size(), actions.size()) << service->Output();
    service->Signal(SIGTERM);
    ASSERT_EQ(service->WaitExit(10s), std::optional<int>(0)) << service->Output();
  }
  ASSERT_TRUE(std::filesystem::exists(map_file));
  ScratchFolder other_state;
  auto loaded = std::make_unique<ChildProcess>(
      kBinary, std::vector<std::string>{"--domain", std::to_string(domain_.id()), "--state-dir",
                                        other_state.path().string(), "--set", "experience_map.load_map=" + map_file});
  const auto map = AwaitMap([&](const msg::ExperienceMap& m) {
    return m.experiences.size() == reference.experiences && m.action_seq == actions.size() - 1;
  });
  ASSERT_TRUE(map) << loaded->Output();
  EXPECT_EQ(map->links.size(), reference.links.size());
}

TEST_F(ExperienceMapServiceTest, TheFinalMapIsPublishedOnStop) {
  // No snapshot while it runs: neither the action count nor the idle time reaches its period.
  auto service = Start({"--set", "experience_map.map_publish_period_frames=100000", "--set",
                        "experience_map.idle_publish_s=60"});
  const auto actions = testing::ScriptedActions(testing::ScriptedLoop(20));
  for (const auto& a : actions) action_pub_->Publish(a);
  ASSERT_EQ(AwaitPoses(actions.size()).size(), actions.size()) << service->Output();
  EXPECT_FALSE(map_sub_->TakeOne(300ms)) << "a snapshot while running";
  service->Signal(SIGTERM);
  ASSERT_EQ(service->WaitExit(10s), std::optional<int>(0)) << service->Output();
  const auto map = AwaitMap([&](const msg::ExperienceMap& m) { return m.action_seq == actions.size() - 1; }, 2s);
  ASSERT_TRUE(map) << service->Output();
  EXPECT_EQ(map->experiences.size(), testing::ApplyAll(actions).experiences);
}

TEST_F(ExperienceMapServiceTest, CorruptStateFileIsRefusedAtStart) {
  std::ofstream(state_dir_.path() / "experience_map.pb") << "not a state file";
  const auto [code, output] = testing::RunToExit(
      kBinary, {"--domain", std::to_string(domain_.id()), "--state-dir", state_dir_.path().string()});
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("experience_map.pb"), std::string::npos) << output;
}

}  // namespace
}  // namespace rslam
