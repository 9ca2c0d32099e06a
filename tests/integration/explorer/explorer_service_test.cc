// rslam-explorer as a black box on a private DDS domain: the test plays the occupancy mapper,
// the experience map and the robot's base.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "common/math/pose2d.h"
#include "common/persistence/state_file.h"
#include "services/explorer/proto/explorer_node_state.pb.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::ScratchFolder;
using testing::WaitFor;
using testing::WaitForNewMatches;

const std::string kBinary = RSLAM_BINARY_DIR "/bin/rslam-explorer";

// 3 m x 3 m around the origin, 5 cm cells.
msg::OccupancyGrid EmptyGrid(int8_t fill) {
  msg::OccupancyGrid g;
  g.header = {"robot1", 1, 100'000'000};
  g.map_version = 1;
  g.width = 60;
  g.height = 60;
  g.resolution_m = 0.05f;
  g.origin_x_m = -1.5;
  g.origin_y_m = -1.5;
  g.cells.assign(60 * 60, fill);
  return g;
}

// Free floor within 0.6 m of the robot, unknown beyond.
msg::OccupancyGrid PartlyExploredGrid() {
  msg::OccupancyGrid g = EmptyGrid(-1);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 60; ++x)
      if (std::hypot(-1.5 + (x + 0.5) * 0.05, -1.5 + (y + 0.5) * 0.05) < 0.6) g.cells[y * 60 + x] = 0;
  return g;
}

// Everything known: free floor inside a wall along the border.
msg::OccupancyGrid FullyExploredGrid() {
  msg::OccupancyGrid g = EmptyGrid(0);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 60; ++x)
      if (x == 0 || y == 0 || x == 59 || y == 59) g.cells[y * 60 + x] = 100;
  g.map_version = 2;
  return g;
}

msg::ExperiencePose RobotAt(double x, double y, double theta, uint64_t seq = 1) {
  msg::ExperiencePose p;
  p.header = {"robot1", seq, static_cast<int64_t>(seq) * 100'000'000};
  p.x_m = x;
  p.y_m = y;
  p.theta_rad = theta;
  return p;
}

class ExplorerServiceTest : public ::testing::Test {
 protected:
  ExplorerServiceTest() {
    bus::BusConfig config;
    config.domain_id = domain_.id();
    participant_ = bus::Participant::Create(config);
    grid_pub_ = std::make_unique<bus::Publisher<msg::OccupancyGrid>>(*participant_, bus::topics::kOccupancyGrid);
    pose_pub_ = std::make_unique<bus::Publisher<msg::ExperiencePose>>(*participant_, bus::topics::kExperienceMapPose);
    feedback_pub_ = std::make_unique<bus::Publisher<msg::MotionFeedback>>(*participant_, bus::topics::kMotionFeedback);
    command_sub_ = std::make_unique<bus::Subscriber<msg::MotionCommand>>(*participant_, bus::topics::kExplorerCommand);
    status_sub_ = std::make_unique<bus::Subscriber<msg::ExplorerStatus>>(*participant_, bus::topics::kExplorerStatus);
    heartbeat_sub_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(*participant_, bus::topics::kStatus);
  }

  std::unique_ptr<ChildProcess> Start(const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args{"--domain", std::to_string(domain_.id()), "--state-dir", state_dir_.path().string(),
                                  "--set", "service.heartbeat_period_s=0.2", "--set",
                                  "explorer.fresh_grid_timeout_s=0.3"};
    args.insert(args.end(), extra.begin(), extra.end());
    auto process = std::make_unique<ChildProcess>(kBinary, args);
    const bool matched = WaitForNewMatches({[&] { return pose_pub_->MatchedSubscribers(); },
                                            [&] { return feedback_pub_->MatchedSubscribers(); },
                                            [&] { return command_sub_->MatchedPublishers(); }},
                                           10s);
    EXPECT_TRUE(matched) << process->Output();
    return process;
  }

  std::optional<msg::MotionCommand> NextCommand(std::chrono::milliseconds timeout = 5s) {
    return command_sub_->TakeOne(timeout);
  }

  void Feedback(uint64_t command_seq, msg::MotionState state) {
    msg::MotionFeedback f;
    f.header = {"robot1", 1, 0};
    f.command_seq = command_seq;
    f.state = state;
    feedback_pub_->Publish(f);
  }

  std::optional<msg::ExplorerStatus> AwaitStatus(const std::function<bool(const msg::ExplorerStatus&)>& pred,
                                                 std::chrono::milliseconds timeout = 10s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto s = status_sub_->TakeOne(200ms); s && pred(*s)) return s;
    }
    return std::nullopt;
  }

  testing::TestDomain domain_;
  ScratchFolder state_dir_;
  std::unique_ptr<bus::Participant> participant_;
  std::unique_ptr<bus::Publisher<msg::OccupancyGrid>> grid_pub_;
  std::unique_ptr<bus::Publisher<msg::ExperiencePose>> pose_pub_;
  std::unique_ptr<bus::Publisher<msg::MotionFeedback>> feedback_pub_;
  std::unique_ptr<bus::Subscriber<msg::MotionCommand>> command_sub_;
  std::unique_ptr<bus::Subscriber<msg::ExplorerStatus>> status_sub_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> heartbeat_sub_;
};

TEST_F(ExplorerServiceTest, WaitsForAGridThenSendsOneCommandAtATime) {
  auto service = Start();
  ASSERT_TRUE(AwaitStatus([](const msg::ExplorerStatus& s) {
    return s.state == msg::ExplorationState::EXPLORATION_WAITING;
  })) << service->Output();
  pose_pub_->Publish(RobotAt(0, 0, 0));
  EXPECT_FALSE(NextCommand(500ms)) << "no command before a grid";

  grid_pub_->Publish(PartlyExploredGrid());
  const auto first = NextCommand();
  ASSERT_TRUE(first) << service->Output();
  EXPECT_NE(first->kind, msg::MotionKind::MOTION_STOP);
  EXPECT_EQ(first->header.robot_id, "robot1");
  EXPECT_FALSE(NextCommand(500ms)) << "a second command before the first one's feedback";

  Feedback(first->command_seq, msg::MotionState::MOTION_EXECUTING);
  EXPECT_FALSE(NextCommand(300ms)) << "EXECUTING is not DONE";
  Feedback(first->command_seq, msg::MotionState::MOTION_DONE);
  const auto second = NextCommand();
  ASSERT_TRUE(second) << service->Output();
  EXPECT_GT(second->command_seq, first->command_seq);
  EXPECT_TRUE(AwaitStatus([](const msg::ExplorerStatus& s) {
    return s.state == msg::ExplorationState::EXPLORATION_EXPLORING && s.commands_sent >= 2;
  })) << service->Output();
}

TEST_F(ExplorerServiceTest, FullyKnownGridCompletesWithStop) {
  auto service = Start();
  pose_pub_->Publish(RobotAt(0, 0, 0));
  grid_pub_->Publish(PartlyExploredGrid());
  auto command = NextCommand();
  ASSERT_TRUE(command) << service->Output();

  grid_pub_->Publish(FullyExploredGrid());
  // Play the base: every command succeeds, until the explorer stops.
  for (int i = 0; i < 30 && command && command->kind != msg::MotionKind::MOTION_STOP; ++i) {
    Feedback(command->command_seq, msg::MotionState::MOTION_DONE);
    command = NextCommand();
  }
  ASSERT_TRUE(command) << service->Output();
  EXPECT_EQ(command->kind, msg::MotionKind::MOTION_STOP);
  const auto status = AwaitStatus([](const msg::ExplorerStatus& s) {
    return s.state == msg::ExplorationState::EXPLORATION_COMPLETE;
  });
  ASSERT_TRUE(status) << service->Output();
  EXPECT_FALSE(status->reason.empty());
}

TEST_F(ExplorerServiceTest, BlockedMoveIsReplanned) {
  auto service = Start();
  pose_pub_->Publish(RobotAt(0, 0, 0));
  grid_pub_->Publish(PartlyExploredGrid());
  auto command = NextCommand();
  ASSERT_TRUE(command) << service->Output();
  Feedback(command->command_seq, msg::MotionState::MOTION_BLOCKED);
  // The explorer waits for a newer grid (or fresh_grid_timeout_s), then plans again.
  grid_pub_->Publish(PartlyExploredGrid());
  const auto replanned = NextCommand();
  ASSERT_TRUE(replanned) << service->Output();
  EXPECT_GT(replanned->command_seq, command->command_seq);
}

// A corridor along +x (walls at |y| = 0.5 m and x = -0.5 m), known up to x = 1.2 m, unknown
// beyond; optionally closed by a wall across it at x = 0.5 m.
msg::OccupancyGrid Corridor(bool closed_ahead) {
  msg::OccupancyGrid g = EmptyGrid(-1);
  for (int cy = 0; cy < 60; ++cy) {
    for (int cx = 0; cx < 60; ++cx) {
      const double x = -1.5 + (cx + 0.5) * 0.05, y = -1.5 + (cy + 0.5) * 0.05;
      int8_t& cell = g.cells[cy * 60 + cx];
      if (std::abs(y) > 0.6 || x < -0.6) continue;  // unknown
      if (std::abs(y) > 0.5 || x < -0.5) cell = 100;
      else if (x < 1.2) cell = closed_ahead && x > 0.5 && x < 0.6 ? 100 : 0;
    }
  }
  return g;
}

TEST_F(ExplorerServiceTest, LooksBeforeMovingAndDoesNotDriveIntoANewWall) {
  auto service = Start();
  pose_pub_->Publish(RobotAt(0, 0, M_PI / 2));  // facing the corridor's side wall
  grid_pub_->Publish(Corridor(/*closed_ahead=*/false));
  const auto turn = NextCommand();
  ASSERT_TRUE(turn) << service->Output();
  ASSERT_EQ(turn->kind, msg::MotionKind::MOTION_ROTATE) << "expected to turn towards the unknown end first";

  // While the robot turns, the map learns of a wall across the corridor.
  grid_pub_->Publish(Corridor(/*closed_ahead=*/true));
  // Its inputs so far: the pose, the first grid and this one (the heartbeat counts them).
  ASSERT_TRUE(WaitFor(
      [&] {
        const auto s = heartbeat_sub_->TakeOne(100ms);
        return s && s->service == "explorer" && s->messages_in >= 3;
      },
      5s));
  Feedback(turn->command_seq, msg::MotionState::MOTION_DONE);
  const auto next = NextCommand();
  ASSERT_TRUE(next) << service->Output();
  EXPECT_NE(next->kind, msg::MotionKind::MOTION_MOVE)
      << "drove into the wall it could see: turned " << turn->angle_rad << ", then moved " << next->distance_m;
}

// Two rooms joined by a door 0.6 m wide in a wall at x = 0.5 m (the walls round them at
// x = -1.25 and 1.4 m, |y| = 0.95 m). `west_unknown`: the west room unknown beyond x < -0.7 m;
// `east_unknown`: the east room unknown beyond x > 0.8 m; `door_drawn_shut`: the grid shows
// the wall across the door as well.
msg::OccupancyGrid TwoRooms(bool west_unknown, bool east_unknown, bool door_drawn_shut) {
  msg::OccupancyGrid g = EmptyGrid(-1);
  for (int cy = 0; cy < 60; ++cy) {
    for (int cx = 0; cx < 60; ++cx) {
      const double x = -1.5 + (cx + 0.5) * 0.05, y = -1.5 + (cy + 0.5) * 0.05;
      int8_t& cell = g.cells[cy * 60 + cx];
      if (x < -1.3 || x > 1.45 || std::abs(y) > 1.0) continue;  // unknown
      const bool wall_between = x > 0.5 && x < 0.55 && (door_drawn_shut || std::abs(y) > 0.3);
      if (x < -1.25 || x > 1.4 || std::abs(y) > 0.95 || wall_between)
        cell = 100;
      else if (!(west_unknown && x < -0.7) && !(east_unknown && x > 0.8))
        cell = 0;
    }
  }
  return g;
}

TEST_F(ExplorerServiceTest, DrivesBackThroughADoorTheGridDrewShutBehindIt) {
  auto service = Start();
  // Plays the base: every command is done as asked; the robot's pose follows.
  Pose2D robot{-0.4, 0.0, 0.0};
  const auto play = [&](const msg::MotionCommand& c) {
    if (c.kind == msg::MotionKind::MOTION_ROTATE) robot.theta += c.angle_rad;
    if (c.kind == msg::MotionKind::MOTION_MOVE)
      robot = {robot.x + c.distance_m * std::cos(robot.theta), robot.y + c.distance_m * std::sin(robot.theta),
               robot.theta};
    pose_pub_->Publish(RobotAt(robot.x, robot.y, robot.theta));
    Feedback(c.command_seq, msg::MotionState::MOTION_DONE);
  };
  pose_pub_->Publish(RobotAt(robot.x, robot.y, robot.theta));
  grid_pub_->Publish(TwoRooms(/*west_unknown=*/false, /*east_unknown=*/true, /*door_drawn_shut=*/false));
  // Through the door to the unknown east.
  std::optional<msg::MotionCommand> command;
  for (int i = 0; i < 20 && robot.x < 0.55; ++i) {
    command = NextCommand();
    ASSERT_TRUE(command) << service->Output();
    ASSERT_NE(command->kind, msg::MotionKind::MOTION_STOP) << service->Output();
    play(*command);
  }
  ASSERT_GT(robot.x, 0.55) << service->Output();
  // Now the east room is known, the map draws the wall across the door, and the west room has
  // unknown space after all. The explorer drives back through the door it came by.
  const msg::OccupancyGrid shut = TwoRooms(/*west_unknown=*/true, /*east_unknown=*/false, /*door_drawn_shut=*/true);
  bool crossed = false;
  for (int i = 0; i < 30 && !crossed; ++i) {
    grid_pub_->Publish(shut);
    command = NextCommand();
    ASSERT_TRUE(command) << service->Output();
    ASSERT_NE(command->kind, msg::MotionKind::MOTION_STOP) << "called exploration complete in the east room\n"
                                                           << service->Output();
    const double x0 = robot.x;
    play(*command);
    crossed = x0 > 0.55 && robot.x < 0.5;
  }
  EXPECT_TRUE(crossed) << service->Output();
}

TEST_F(ExplorerServiceTest, UnansweredCommandIsPlannedAgainAfterTheTimeout) {
  auto service = Start({"--set", "explorer.feedback_timeout_s=0.5"});
  pose_pub_->Publish(RobotAt(0, 0, 0));
  grid_pub_->Publish(PartlyExploredGrid());
  const auto first = NextCommand();
  ASSERT_TRUE(first) << service->Output();
  // The base never answers: the explorer gives up on the command and plans afresh.
  const auto again = NextCommand(5s);
  ASSERT_TRUE(again) << service->Output();
  EXPECT_GT(again->command_seq, first->command_seq);
  EXPECT_TRUE(AwaitStatus([](const msg::ExplorerStatus& s) { return s.reason.find("no feedback") != std::string::npos; }))
      << service->Output();
}

TEST_F(ExplorerServiceTest, MalformedGridIsCountedAndTheServiceKeepsRunning) {
  auto service = Start();
  msg::OccupancyGrid bad = PartlyExploredGrid();
  bad.cells.resize(bad.cells.size() - 7);  // cells do not match width x height
  grid_pub_->Publish(bad);
  pose_pub_->Publish(RobotAt(0, 0, 0));
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  bool counted = false;
  while (!counted && std::chrono::steady_clock::now() < deadline) {
    if (auto s = heartbeat_sub_->TakeOne(200ms); s && s->service == "explorer" && s->messages_rejected >= 1)
      counted = true;
  }
  EXPECT_TRUE(counted) << service->Output();
  EXPECT_FALSE(NextCommand(300ms)) << "planned on a malformed grid";
  EXPECT_TRUE(service->Running());

  grid_pub_->Publish(PartlyExploredGrid());
  EXPECT_TRUE(NextCommand()) << service->Output();
}

TEST_F(ExplorerServiceTest, StoppingCancelsTheCommandAndRestartKeepsNumberingUpwards) {
  uint64_t first_run_seq = 0;
  {
    auto service = Start();
    pose_pub_->Publish(RobotAt(0, 0, 0));
    grid_pub_->Publish(PartlyExploredGrid());
    const auto command = NextCommand();
    ASSERT_TRUE(command) << service->Output();
    service->Signal(SIGTERM);
    ASSERT_EQ(service->WaitExit(10s), 0) << service->Output();
    // The outstanding command is cancelled: the robot must not drive on unwatched.
    const auto stop = NextCommand();
    ASSERT_TRUE(stop) << service->Output();
    EXPECT_EQ(stop->kind, msg::MotionKind::MOTION_STOP);
    EXPECT_GT(stop->command_seq, command->command_seq);
    first_run_seq = stop->command_seq;
    EXPECT_TRUE(AwaitStatus([](const msg::ExplorerStatus& s) {
      return s.state == msg::ExplorationState::EXPLORATION_STOPPED;
    }));
  }
  EXPECT_TRUE(std::filesystem::exists(state_dir_.path() / "explorer.pb"));
  // A clean exit: its readers and writer leave at once.
  EXPECT_TRUE(WaitFor([&] { return pose_pub_->MatchedSubscribers() == 0 && command_sub_->MatchedPublishers() == 0; }, 5s));
  auto restarted = Start();
  pose_pub_->Publish(RobotAt(0, 0, 0));  // the grid comes again from the state topic
  const auto command = NextCommand();
  ASSERT_TRUE(command) << restarted->Output();
  EXPECT_GT(command->command_seq, first_run_seq);
}

TEST_F(ExplorerServiceTest, RestartAfterSigkillContinuesFromTheLastPeriodicSave) {
  const std::string state_file = (state_dir_.path() / "explorer.pb").string();
  uint64_t first_seq = 0;
  {
    auto service = Start({"--set", "service.state_save_period_s=0.2"});
    pose_pub_->Publish(RobotAt(0, 0, 0));
    grid_pub_->Publish(PartlyExploredGrid());
    const auto command = NextCommand();
    ASSERT_TRUE(command) << service->Output();
    first_seq = command->command_seq;
    // A periodic save holds the command (never a shutdown save: the process is killed).
    ASSERT_TRUE(WaitFor([&] {
      explorer::proto::ExplorerNodeState saved;
      try {
        ReadStateFile(state_file, "rslam.explorer.ExplorerNodeState", 1, saved);
      } catch (const StateFileError&) {
        return false;  // not written yet
      }
      return saved.last_command_seq() >= first_seq;
    }, 5s)) << service->Output();
    service->Signal(SIGKILL);
    ASSERT_TRUE(service->WaitExit(10s)) << service->Output();
  }
  auto restarted = Start();
  pose_pub_->Publish(RobotAt(0, 0, 0));  // the grid comes again from the state topic
  const auto command = NextCommand();
  ASSERT_TRUE(command) << restarted->Output();
  EXPECT_GT(command->command_seq, first_seq) << restarted->Output();
  EXPECT_NE(restarted->Output().find("loaded explorer state"), std::string::npos) << restarted->Output();
}

TEST(ExplorerServiceCommandLineTest, HelpListsConfigKeys) {
  const auto [code, output] = testing::RunToExit(kBinary, {"--help"});
  EXPECT_EQ(code, 0) << output;
  for (const char* key : {"explorer.robot_radius_m", "explorer.coarse_cell_factor", "explorer.feedback_timeout_s"})
    EXPECT_NE(output.find(key), std::string::npos) << key;
}

TEST(ExplorerServiceCommandLineTest, UnknownConfigKeyExitsTwoNamingIt) {
  const auto [code, output] = testing::RunToExit(kBinary, {"--set", "explorer.unknown_key=1"});
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("explorer.unknown_key"), std::string::npos) << output;
}

}  // namespace
}  // namespace rslam
