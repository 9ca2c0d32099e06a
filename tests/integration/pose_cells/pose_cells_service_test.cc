// rslam-pose-cells as a process on the test's own DDS domain: odometry and views in, one
// pose-cell action per frame out.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "services/pose_cells/pose_cell_network.h"
#include "tests/support/child_process.h"
#include "tests/integration/pose_cells/scripted_loop.h"
#include "tests/support/floor_boundary_scans.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;
using testing::ScriptedFrame;
using testing::ChildProcess;
using testing::ScratchFolder;
using testing::WaitFor;

const std::string kBinary = RSLAM_BINARY_DIR "/bin/rslam-pose-cells";

msg::ActionKind KindOf(pose_cells::Action::Kind k) {
  switch (k) {
    case pose_cells::Action::Kind::kCreate: return msg::ActionKind::ACTION_CREATE;
    case pose_cells::Action::Kind::kLink: return msg::ActionKind::ACTION_LINK;
    case pose_cells::Action::Kind::kSet: return msg::ActionKind::ACTION_SET;
    case pose_cells::Action::Kind::kNone: break;
  }
  return msg::ActionKind::ACTION_NONE;
}

class PoseCellsServiceTest : public ::testing::Test {
 protected:
  PoseCellsServiceTest() {
    bus::BusConfig config;
    config.ApplyEnvironment();  // RSLAM_DDS picks the vendor of the test and the services alike
    config.domain_id = domain_.id();
    participant_ = bus::Participant::Create(config);
    velocity_pub_ = std::make_unique<bus::Publisher<msg::Velocity>>(*participant_, bus::topics::kOdometryVelocity);
    view_pub_ = std::make_unique<bus::Publisher<msg::ViewTemplate>>(*participant_, bus::topics::kTemplatesView);
    action_sub_ = std::make_unique<bus::Subscriber<msg::PoseCellAction>>(*participant_, bus::topics::kPoseCellsAction);
    status_sub_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(*participant_, bus::topics::kStatus);
  }

  std::unique_ptr<ChildProcess> Start(const std::vector<std::string>& extra_args = {}) {
    std::vector<std::string> args{"--domain", std::to_string(domain_.id()), "--state-dir",
                                  state_dir_.path().string(), "--set", "service.heartbeat_period_s=0.2",
                                  "--set", "pose_cells.resync_timeout_s=0"};
    args.insert(args.end(), extra_args.begin(), extra_args.end());
    auto process = std::make_unique<ChildProcess>(kBinary, args);
    const bool matched = WaitFor(
        [&] {
          return velocity_pub_->MatchedSubscribers() > 0 && view_pub_->MatchedSubscribers() > 0 &&
                 action_sub_->MatchedPublishers() > 0;
        },
        10s);
    EXPECT_TRUE(matched) << process->Output();
    return process;
  }

  std::vector<msg::PoseCellAction> AwaitActions(size_t n, std::chrono::milliseconds timeout = 10s) {
    std::vector<msg::PoseCellAction> out;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (out.size() < n && std::chrono::steady_clock::now() < deadline) {
      if (auto a = action_sub_->TakeOne(100ms)) out.push_back(*a);
    }
    return out;
  }

  // Each frame's odometry then its view, then the actions of them all.
  std::vector<msg::PoseCellAction> Drive(const std::vector<ScriptedFrame>& script) {
    for (const ScriptedFrame& f : script) {
      velocity_pub_->Publish(f.velocity);
      view_pub_->Publish(f.view);
    }
    return AwaitActions(script.size());
  }

  std::optional<msg::ServiceStatus> AwaitStatus(uint64_t min_rejected, std::chrono::milliseconds timeout = 5s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto s = status_sub_->TakeOne(100ms); s && s->service == "pose_cells" && s->messages_rejected >= min_rejected)
        return s;
    }
    return std::nullopt;
  }

  testing::TestDomain domain_;
  ScratchFolder state_dir_;
  std::unique_ptr<bus::Participant> participant_;
  std::unique_ptr<bus::Publisher<msg::Velocity>> velocity_pub_;
  std::unique_ptr<bus::Publisher<msg::ViewTemplate>> view_pub_;
  std::unique_ptr<bus::Subscriber<msg::PoseCellAction>> action_sub_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> status_sub_;
};

TEST_F(PoseCellsServiceTest, OneActionPerFrameInOrderCreatesThenLinksWhenTheFirstViewReturns) {
  auto service = Start();
  const int frames = testing::kLapFrames + 10;
  const std::vector<ScriptedFrame> script = testing::ScriptedLoop(frames);
  // The two topics interleave out of order: a block's views first, then its odometry.
  for (int block = 0; block < frames; block += 5) {
    for (int i = block; i < block + 5 && i < frames; ++i) view_pub_->Publish(script[i].view);
    for (int i = block; i < block + 5 && i < frames; ++i) velocity_pub_->Publish(script[i].velocity);
  }
  const auto actions = AwaitActions(frames);
  ASSERT_EQ(actions.size(), static_cast<size_t>(frames)) << service->Output();

  // The same frames through the library: the service adds nothing and loses nothing.
  pose_cells::PoseCellNetwork reference(pose_cells::PoseCellConfig{});
  int creates = 0, first_link = -1;
  for (int i = 0; i < frames; ++i) {
    const ScriptedFrame& f = script[i];
    const pose_cells::Action want = reference.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps, f.velocity.dt_s,
                                                           MatchOf(f));
    const msg::PoseCellAction& got = actions[i];
    EXPECT_EQ(got.action_seq, static_cast<uint64_t>(i));
    EXPECT_EQ(got.header, f.velocity.header);
    EXPECT_EQ(got.kind, KindOf(want.kind)) << "frame " << i;
    EXPECT_EQ(got.vtrans_mps, f.velocity.vtrans_mps);
    EXPECT_EQ(got.vrot_radps, f.velocity.vrot_radps);
    EXPECT_EQ(got.dt_s, f.velocity.dt_s);
    if (want.kind != pose_cells::Action::Kind::kNone) {
      EXPECT_EQ(got.experience_id, want.experience_id) << "frame " << i;
      EXPECT_EQ(got.from_experience_id, want.from_experience_id) << "frame " << i;
    }
    if (got.kind == msg::ActionKind::ACTION_CREATE) ++creates;
    if (got.kind == msg::ActionKind::ACTION_LINK && first_link < 0) first_link = i;
  }
  EXPECT_EQ(actions[0].kind, msg::ActionKind::ACTION_CREATE);
  EXPECT_EQ(actions[0].experience_id, 0u);
  EXPECT_GE(creates, 8);
  ASSERT_GE(first_link, testing::kLapFrames) << "the loop closes when the first view returns, not before";
  EXPECT_LE(first_link, testing::kLapFrames + 2);
  EXPECT_EQ(actions[first_link].experience_id, 0u);
  EXPECT_TRUE(service->Running());
  if (HasFailure()) ADD_FAILURE() << service->Output();
}

// A scan of the support header as the odometry's message carries it.
std::vector<msg::FloorPoint> Message(const std::vector<Eigen::Vector2f>& scan) {
  std::vector<msg::FloorPoint> points;
  for (const Eigen::Vector2f& p : scan) points.push_back({p.x(), p.y()});
  return points;
}

TEST_F(PoseCellsServiceTest, BoundaryCheckRefusesTheLoopClosureWhenTheWallsDisagree) {
  auto service = Start({"--set", "pose_cells.exp_boundary_check=true", "--set",
                        "pose_cells.exp_boundary_min_age_frames=50"});
  const int frames = testing::kLapFrames + 10;
  std::vector<ScriptedFrame> script = testing::ScriptedLoop(frames);
  for (int i = 0; i < frames; ++i) {  // the first lap sees a corner, the second a corridor
    script[i].velocity.boundary_measured = true;
    script[i].velocity.boundary = Message(i < testing::kLapFrames ? testing::CornerScan() : testing::CorridorScan());
  }
  const auto actions = Drive(script);
  ASSERT_EQ(actions.size(), static_cast<size_t>(frames)) << service->Output();
  // The library with the same check and boundaries decides alike; without them it would link.
  pose_cells::PoseCellConfig config;
  config.exp_boundary_check = true;
  config.exp_boundary_min_age_frames = 50;
  pose_cells::PoseCellNetwork reference(config), unchecked(pose_cells::PoseCellConfig{});
  int refused = 0, links = 0, unchecked_links = 0;
  for (int i = 0; i < frames; ++i) {
    const ScriptedFrame& f = script[i];
    pose_cells::FloorBoundary boundary;
    for (const msg::FloorPoint& p : f.velocity.boundary) boundary.emplace_back(p.x_m, p.y_m);
    const pose_cells::Action want = reference.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps,
                                                           f.velocity.dt_s, MatchOf(f),
                                                           &boundary);
    const pose_cells::Action plain = unchecked.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps,
                                                            f.velocity.dt_s, MatchOf(f));
    EXPECT_EQ(actions[i].kind, KindOf(want.kind)) << "frame " << i;
    if (want.kind != pose_cells::Action::Kind::kNone) {
      EXPECT_EQ(actions[i].experience_id, want.experience_id) << i;
    }
    refused += want.refused_link_to != pose_cells::kNoExperience;
    links += actions[i].kind == msg::ActionKind::ACTION_LINK;
    unchecked_links += plain.kind == pose_cells::Action::Kind::kLink;
  }
  EXPECT_GE(unchecked_links, 1);
  EXPECT_EQ(links, 0);
  EXPECT_GE(refused, 1);
  if (HasFailure()) ADD_FAILURE() << service->Output();
}

// exp_view_offset: the service hands the views' differences to the network, whose links and
// sets then carry the offset measured from the best recent view.
TEST_F(PoseCellsServiceTest, ViewOffsetRidesOnTheRecognitionsAsTheLibraryMeasuresIt) {
  auto service = Start({"--set", "pose_cells.exp_view_offset=true"});
  const int frames = testing::kLapFrames + 10;
  std::vector<ScriptedFrame> script = testing::ScriptedLoop(frames);
  for (int i = 0; i < frames; ++i) script[i].view.difference = 0.01 * ((i * 7) % 5);
  const auto actions = Drive(script);
  ASSERT_EQ(actions.size(), static_cast<size_t>(frames)) << service->Output();
  pose_cells::PoseCellConfig config;
  config.exp_view_offset = true;
  pose_cells::PoseCellNetwork reference(config);
  int recognitions = 0, measured = 0;
  for (int i = 0; i < frames; ++i) {
    const ScriptedFrame& f = script[i];
    const pose_cells::Action want =
        reference.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps, f.velocity.dt_s, MatchOf(f));
    ASSERT_EQ(actions[i].kind, KindOf(want.kind)) << "frame " << i;
    EXPECT_EQ(actions[i].offset_x_m, want.offset_x_m) << "frame " << i;
    EXPECT_EQ(actions[i].offset_y_m, want.offset_y_m) << "frame " << i;
    recognitions += want.kind == pose_cells::Action::Kind::kLink || want.kind == pose_cells::Action::Kind::kSet;
    measured += want.offset_x_m != 0.0 || want.offset_y_m != 0.0;
  }
  EXPECT_GE(recognitions, 1);
  EXPECT_GE(measured, 1);
  if (HasFailure()) ADD_FAILURE() << service->Output();
}

// exp_submap_offset alone: the service keeps the floor boundaries for it (the check and the
// other offsets off) and its links and sets carry the offset the library registers from both
// laps' walls. The laps run down a corridor ringing the square, the second 0.3 m north of the
// first (the same odometry); once the last 30 frames lie on the second lap the walls say so,
// along the south side and round its corner (further up the east side the shift runs along the
// corridor, where the point-to-point registration slides: not driven here).
TEST_F(PoseCellsServiceTest, SubmapOffsetRidesOnTheRecognitionsAsTheLibraryMeasuresIt) {
  auto service = Start({"--set", "pose_cells.exp_submap_offset=true", "--set",
                        "pose_cells.exp_submap_min_age_frames=50"});
  // The walls either side of the path, pillars 0.4 m deep on the outer ones every 2 m.
  std::vector<testing::Wall> ring = {{-1, -1, 11, -1}, {11, -1, 11, 11}, {11, 11, -1, 11}, {-1, 11, -1, -1},
                                     {1, 1, 9, 1},     {9, 1, 9, 9},     {9, 9, 1, 9},     {1, 9, 1, 1}};
  for (double a = 2.0; a < 9.0; a += 2.0) {
    ring.push_back({a, -1, a, -0.6});  // south side
    ring.push_back({a, -0.6, a + 0.4, -0.6});
    ring.push_back({a + 0.4, -0.6, a + 0.4, -1});
    ring.push_back({11, a, 10.6, a});  // east side
    ring.push_back({10.6, a, 10.6, a + 0.4});
    ring.push_back({10.6, a + 0.4, 11, a + 0.4});
  }
  const int frames = testing::kLapFrames + 37;
  std::vector<ScriptedFrame> script = testing::ScriptedLoop(frames);
  std::vector<double> heading(frames);  // the odometry's, after each frame
  Pose2D odometry;                      // as the network dead-reckons it
  for (int i = 0; i < frames; ++i) {
    const msg::Velocity& v = script[i].velocity;
    odometry = Compose(odometry, {v.vtrans_mps * v.dt_s, 0.0, v.vrot_radps * v.dt_s});
    heading[i] = odometry.theta;
    script[i].velocity.boundary_measured = true;
    script[i].velocity.boundary = Message(testing::ScanOfWalls(
        ring, odometry.x, odometry.y + (i < testing::kLapFrames ? 0.0 : 0.3), odometry.theta));
  }
  const auto actions = Drive(script);
  ASSERT_EQ(actions.size(), static_cast<size_t>(frames)) << service->Output();
  pose_cells::PoseCellConfig config;
  config.exp_submap_offset = true;
  config.exp_submap_min_age_frames = 50;
  pose_cells::PoseCellNetwork reference(config);
  std::vector<double> made_facing;  // per experience
  int measured = 0;
  for (int i = 0; i < frames; ++i) {
    const ScriptedFrame& f = script[i];
    pose_cells::FloorBoundary boundary;
    for (const msg::FloorPoint& p : f.velocity.boundary) boundary.emplace_back(p.x_m, p.y_m);
    const pose_cells::Action want = reference.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps,
                                                           f.velocity.dt_s, MatchOf(f), &boundary);
    ASSERT_EQ(actions[i].kind, KindOf(want.kind)) << "frame " << i;
    EXPECT_EQ(actions[i].offset_x_m, want.offset_x_m) << "frame " << i;
    EXPECT_EQ(actions[i].offset_y_m, want.offset_y_m) << "frame " << i;
    if (want.kind == pose_cells::Action::Kind::kCreate) made_facing.push_back(heading[i]);
    if (want.kind != pose_cells::Action::Kind::kLink && want.kind != pose_cells::Action::Kind::kSet) continue;
    if (want.offset_x_m == 0.0 && want.offset_y_m == 0.0) continue;  // the walls did not register yet
    ASSERT_LT(want.experience_id, made_facing.size());
    // 0.3 m north, in the frame of the experience (made facing made_facing).
    const double facing = made_facing[want.experience_id];
    EXPECT_NEAR(want.offset_x_m, 0.3 * std::sin(facing), 0.03) << "frame " << i;
    EXPECT_NEAR(want.offset_y_m, 0.3 * std::cos(facing), 0.03) << "frame " << i;
    ++measured;
  }
  EXPECT_GE(measured, 8);
  if (HasFailure()) ADD_FAILURE() << service->Output();
}

TEST_F(PoseCellsServiceTest, MalformedInputIsCountedAndTheServiceKeepsRunning) {
  auto service = Start();
  std::vector<ScriptedFrame> script = testing::ScriptedLoop(12);
  script[5].velocity.vtrans_mps = std::numeric_limits<double>::quiet_NaN();
  script[6].view.template_id = 500;  // 500 templates learnt in one frame: impossible
  script[6].view.template_count = 501;
  script[7].velocity.dt_s = -0.1;
  script[8].view.relative_angle_rad = std::numeric_limits<double>::infinity();
  script[9].velocity.boundary_measured = true;
  script[9].velocity.boundary = {{0.5f, std::numeric_limits<float>::quiet_NaN()}};
  script[10].view.difference = -1.0;
  // Every frame still gives its action: a refused side is processed as missing.
  const auto actions = Drive(script);
  ASSERT_EQ(actions.size(), script.size()) << service->Output();
  for (size_t i = 0; i < actions.size(); ++i) {
    EXPECT_EQ(actions[i].action_seq, i);
    EXPECT_EQ(actions[i].header.frame_seq, i);
    EXPECT_TRUE(std::isfinite(actions[i].vtrans_mps));
  }
  EXPECT_EQ(actions[5].vtrans_mps, 0.0);  // refused odometry = no motion
  EXPECT_EQ(actions[5].dt_s, 0.1);        // but the time between the frames still passed
  const auto status = AwaitStatus(5);
  ASSERT_TRUE(status) << service->Output();
  EXPECT_GE(status->messages_rejected, 6u);
  EXPECT_TRUE(service->Running());
}

TEST_F(PoseCellsServiceTest, AViewThatComesLateKeepsTheTemplateIdsInStep) {
  // A starved template learner (a demo run on a loaded machine): frame 10's view, which learnt
  // template 5, comes after the frame went on without it (here: after frame 11's view, so the
  // view stream has passed frame 10). Its template keeps its id, so the views after it, learning
  // templates 6, 7, ..., are taken (before, each new one was refused as skipping one, for good).
  auto service = Start();
  std::vector<ScriptedFrame> script = testing::ScriptedLoop(30);
  ASSERT_TRUE(script[10].view.is_new);
  // Frame 11 learns a template too (template 5 is not seen again before 6 is learnt).
  for (int i = 11; i < 30; ++i) {
    ++script[i].view.template_id;
    ++script[i].view.template_count;
  }
  script[11].view.is_new = true;
  for (const ScriptedFrame& f : script) velocity_pub_->Publish(f.velocity);
  for (int i : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 11}) view_pub_->Publish(script[i].view);
  std::vector<msg::PoseCellAction> actions = AwaitActions(11);  // frame 10 without its view
  ASSERT_EQ(actions.size(), 11u) << service->Output();
  for (int i = 10; i < 30; ++i)
    if (i != 11) view_pub_->Publish(script[i].view);
  actions = AwaitActions(19);
  ASSERT_EQ(actions.size(), 19u) << service->Output();
  EXPECT_EQ(actions.back().header.frame_seq, 29u);
  // Two rejections: frame 10 processed without its view, and the view that came after it. A
  // heartbeat after every frame was processed says so (they come every 0.2 s).
  ASSERT_TRUE(AwaitStatus(2)) << service->Output();
  std::optional<msg::ServiceStatus> last;
  for (const auto until = std::chrono::steady_clock::now() + 1s; std::chrono::steady_clock::now() < until;)
    if (auto s = status_sub_->TakeOne(100ms); s && s->service == "pose_cells") last = s;
  ASSERT_TRUE(last);
  EXPECT_EQ(last->messages_rejected, 2u) << service->Output();
  EXPECT_TRUE(service->Running());
}

TEST_F(PoseCellsServiceTest, SigtermSavesStateAndRestartContinuesTheActionSequence) {
  auto service = Start();
  const std::vector<ScriptedFrame> script = testing::ScriptedLoop(40);
  for (int i = 0; i < 20; ++i) {
    velocity_pub_->Publish(script[i].velocity);
    view_pub_->Publish(script[i].view);
  }
  ASSERT_EQ(AwaitActions(20).size(), 20u) << service->Output();
  service->Signal(SIGTERM);
  ASSERT_EQ(service->WaitExit(10s), std::optional<int>(0)) << service->Output();
  ASSERT_TRUE(std::filesystem::exists(state_dir_.path() / "pose_cells.pb"));

  auto restarted = Start();
  for (int i = 20; i < 40; ++i) {
    velocity_pub_->Publish(script[i].velocity);
    view_pub_->Publish(script[i].view);
  }
  const auto actions = AwaitActions(20);
  ASSERT_EQ(actions.size(), 20u) << restarted->Output();
  // The same actions an uninterrupted network gives.
  pose_cells::PoseCellNetwork reference(pose_cells::PoseCellConfig{});
  for (int i = 0; i < 40; ++i) {
    const ScriptedFrame& f = script[i];
    const auto want = reference.ProcessFrame(f.velocity.vtrans_mps, f.velocity.vrot_radps, f.velocity.dt_s, MatchOf(f));
    if (i < 20) continue;
    EXPECT_EQ(actions[i - 20].action_seq, static_cast<uint64_t>(i));
    EXPECT_EQ(actions[i - 20].kind, KindOf(want.kind)) << "frame " << i;
    if (want.kind != pose_cells::Action::Kind::kNone) {
      EXPECT_EQ(actions[i - 20].experience_id, want.experience_id);
    }
  }
}

TEST_F(PoseCellsServiceTest, AFailedSaveIsTriedAgainAtTheNextSave) {
  auto service = Start({"--set", "service.state_save_period_s=0.2"});
  // A file where the state folder was: every save fails until the folder is back.
  std::filesystem::remove_all(state_dir_.path());
  std::ofstream(state_dir_.path()) << "not a folder";
  const std::vector<ScriptedFrame> script = testing::ScriptedLoop(20);
  for (const ScriptedFrame& f : script) {
    velocity_pub_->Publish(f.velocity);
    view_pub_->Publish(f.view);
  }
  ASSERT_EQ(AwaitActions(20).size(), 20u) << service->Output();
  ASSERT_TRUE(WaitFor([&] { return service->Output().find("could not save state") != std::string::npos; }, 10s))
      << service->Output();
  std::filesystem::remove(state_dir_.path());
  std::filesystem::create_directories(state_dir_.path());
  // No new input: only a retry of the failed save writes the file.
  EXPECT_TRUE(WaitFor([&] { return std::filesystem::exists(state_dir_.path() / "pose_cells.pb"); }, 10s))
      << service->Output();
  service->Signal(SIGTERM);
  ASSERT_EQ(service->WaitExit(10s), std::optional<int>(0)) << service->Output();
}

TEST_F(PoseCellsServiceTest, AStopPastItsTimeoutEndsTheProcess) {
  // A 1 ms budget runs out during the stop (saving the state and leaving the bus take longer):
  // the process says so and exits 0 instead of waiting to be killed.
  auto service = Start({"--set", "service.stop_timeout_s=0.001"});
  const std::vector<ScriptedFrame> script = testing::ScriptedLoop(5);
  for (const ScriptedFrame& f : script) {
    velocity_pub_->Publish(f.velocity);
    view_pub_->Publish(f.view);
  }
  ASSERT_EQ(AwaitActions(5).size(), 5u) << service->Output();
  service->Signal(SIGTERM);
  ASSERT_EQ(service->WaitExit(10s), std::optional<int>(0)) << service->Output();
  EXPECT_NE(service->Output().find("the stop did not finish within 1 ms: exiting without it"), std::string::npos)
      << service->Output();
}

TEST_F(PoseCellsServiceTest, CorruptStateFileIsRefusedAtStart) {
  std::ofstream(state_dir_.path() / "pose_cells.pb") << "not a state file";
  const auto [code, output] = testing::RunToExit(
      kBinary, {"--domain", std::to_string(domain_.id()), "--state-dir", state_dir_.path().string()});
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("pose_cells.pb"), std::string::npos) << output;
}

TEST_F(PoseCellsServiceTest, UnknownConfigKeyExitsTwoNamingTheKey) {
  const auto [code, output] =
      testing::RunToExit(kBinary, {"--domain", std::to_string(domain_.id()), "--set", "pose_cells.pc_dim_zz=3"});
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("pose_cells.pc_dim_zz"), std::string::npos) << output;
}

TEST_F(PoseCellsServiceTest, ANonPositiveStopTimeoutExitsTwoNamingTheKey) {
  const auto [code, output] =
      testing::RunToExit(kBinary, {"--domain", std::to_string(domain_.id()), "--set", "service.stop_timeout_s=0"});
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("stop_timeout_s"), std::string::npos) << output;
}

}  // namespace
}  // namespace rslam
