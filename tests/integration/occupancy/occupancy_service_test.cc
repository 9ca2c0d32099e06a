// rslam-occupancy as a black box on a private DDS domain: camera frames rendered by the
// simulator's renderer in a room with a wall 1 m ahead, with matching experience-map poses.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "common/persistence/state_file.h"
#include "services/occupancy/proto/occupancy_state.pb.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"
#include <opencv2/imgproc.hpp>

#include "tools/sim/camera_renderer.h"
#include "tools/sim/world_map.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::ScratchFolder;
using testing::WaitFor;
using testing::WaitForNewMatches;

const std::string kBinary = RSLAM_BINARY_DIR "/bin/rslam-occupancy";
constexpr double kWallX = 1.0;  // the wall's face, metres ahead of the robot at the origin

// A 4 m x 4 m room around the origin (the map border is a wall) with a wall across it at x = 1 m.
sim::WorldMap RoomWithWallAhead() {
  constexpr double kResolution = 0.02;
  constexpr int kSize = 200;
  std::vector<sim::CellClass> cells(kSize * kSize, sim::CellClass::kFree);
  const int wall_ix = static_cast<int>(std::lround((kWallX + 2.0) / kResolution));
  for (int iy = 0; iy < kSize; ++iy)
    for (int ix = wall_ix; ix < kSize; ++ix) cells[iy * kSize + ix] = sim::CellClass::kOccupied;
  return sim::WorldMap(kSize, kSize, kResolution, Eigen::Vector2d(-2.0, -2.0), std::move(cells));
}

int8_t CellAt(const msg::OccupancyGrid& g, double x, double y) {
  const int cx = static_cast<int>(std::floor((x - g.origin_x_m) / g.resolution_m));
  const int cy = static_cast<int>(std::floor((y - g.origin_y_m) / g.resolution_m));
  return g.cells.at(static_cast<size_t>(cy) * g.width + cx);
}

// Highest occupancy along y = 0 between x0 and x1 (unknown counts as -1).
int MaxAlongX(const msg::OccupancyGrid& g, double x0, double x1) {
  int best = -1;
  for (double x = x0; x <= x1; x += g.resolution_m * 0.5) best = std::max<int>(best, CellAt(g, x, 0.0));
  return best;
}

class OccupancyServiceTest : public ::testing::Test {
 protected:
  OccupancyServiceTest() : world_(RoomWithWallAhead()), renderer_(world_, sim::SceneConfig{}, sim::CameraConfig{}) {
    bus::BusConfig config;
    config.domain_id = domain_.id();
    participant_ = bus::Participant::Create(config);
    image_pub_ = std::make_unique<bus::Publisher<msg::Image>>(*participant_, bus::topics::kCameraImage);
    pose_pub_ = std::make_unique<bus::Publisher<msg::ExperiencePose>>(*participant_, bus::topics::kExperienceMapPose);
    map_pub_ = std::make_unique<bus::Publisher<msg::ExperienceMap>>(*participant_, bus::topics::kExperienceMapMap);
    profile_sub_ = std::make_unique<bus::Subscriber<msg::ObstacleProfile>>(*participant_, bus::topics::kOccupancyProfile);
    grid_sub_ = std::make_unique<bus::Subscriber<msg::OccupancyGrid>>(*participant_, bus::topics::kOccupancyGrid);
    status_sub_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(*participant_, bus::topics::kStatus);
  }

  std::unique_ptr<ChildProcess> Start(const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args{"--domain", std::to_string(domain_.id()), "--state-dir", state_dir_.path().string(),
                                  "--set", "service.heartbeat_period_s=0.2", "--set",
                                  "service.state_save_period_s=0.3"};
    args.insert(args.end(), extra.begin(), extra.end());
    // Up when its publishers and subscribers have matched ours (a killed predecessor stays matched
    // until its lease expires).
    auto process = std::make_unique<ChildProcess>(kBinary, args);
    const bool matched = WaitForNewMatches({[&] { return image_pub_->MatchedSubscribers(); },
                                            [&] { return pose_pub_->MatchedSubscribers(); },
                                            [&] { return profile_sub_->MatchedPublishers(); },
                                            [&] { return grid_sub_->MatchedPublishers(); }},
                                           10s);
    EXPECT_TRUE(matched) << process->Output();
    return process;
  }

  msg::Image Frame(uint64_t seq, const Pose2D& pose) {
    const cv::Mat bgr = renderer_.Render(pose, seq);
    msg::Image image;
    image.header = {"robot1", seq, static_cast<int64_t>(seq) * 100'000'000};
    image.width = static_cast<uint32_t>(bgr.cols);
    image.height = static_cast<uint32_t>(bgr.rows);
    image.encoding = "bgr8";
    image.step = static_cast<uint32_t>(bgr.cols * 3);
    image.data.assign(bgr.data, bgr.data + bgr.total() * 3);
    return image;
  }

  static msg::ExperiencePose Pose(uint64_t seq, double x, double y, double theta, uint32_t experience_id = 1,
                                  uint64_t map_version = 1) {
    msg::ExperiencePose pose;
    pose.header = {"robot1", seq, static_cast<int64_t>(seq) * 100'000'000};
    pose.current_experience_id = experience_id;
    pose.x_m = x;
    pose.y_m = y;
    pose.theta_rad = theta;
    pose.experience_x_m = 0.0;  // the experience sits at the map origin
    pose.experience_y_m = 0.0;
    pose.experience_theta_rad = 0.0;
    pose.experience_count = 1;
    pose.map_version = map_version;
    return pose;
  }

  // A map snapshot: experience 1 moved to (experience_x, 0).
  static msg::ExperienceMap Correction(uint64_t version, double experience_x) {
    msg::ExperienceMap map;
    map.header = {"robot1", 10, 1'000'000'000};
    map.map_version = version;
    map.current_experience_id = 1;
    msg::Experience e;
    e.id = 1;
    e.x_m = experience_x;
    map.experiences.push_back(e);
    return map;
  }

  // Publishes the frame taken at the origin (pose first or image first; the pose from that map
  // version, which puts the robot at x = map_x) and waits for its profile.
  std::optional<msg::ObstacleProfile> SendFrame(uint64_t seq, bool pose_first = true, uint64_t map_version = 1,
                                                double map_x = 0.0) {
    const msg::Image image = Frame(seq, Pose2D{0, 0, 0});
    const msg::ExperiencePose pose = Pose(seq, map_x, 0, 0, 1, map_version);
    if (pose_first) {
      pose_pub_->Publish(pose);
      image_pub_->Publish(image);
    } else {
      image_pub_->Publish(image);
      pose_pub_->Publish(pose);
    }
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto p = profile_sub_->TakeOne(200ms); p && p->header.frame_seq == seq) return p;
    }
    return std::nullopt;
  }

  // The next grid satisfying pred, within the timeout.
  std::optional<msg::OccupancyGrid> AwaitGrid(const std::function<bool(const msg::OccupancyGrid&)>& pred,
                                              std::chrono::milliseconds timeout = 5s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto g = grid_sub_->TakeOne(200ms); g && pred(*g)) return g;
    }
    return std::nullopt;
  }

  std::optional<msg::ServiceStatus> AwaitStatus(const std::function<bool(const msg::ServiceStatus&)>& pred) {
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (std::chrono::steady_clock::now() < deadline) {
      if (auto s = status_sub_->TakeOne(200ms); s && s->service == "occupancy" && pred(*s)) return s;
    }
    return std::nullopt;
  }

  static bool ShowsWallAhead(const msg::OccupancyGrid& g, double wall_x) {
    return MaxAlongX(g, wall_x - 0.1, wall_x + 0.1) >= 65 && MaxAlongX(g, 0.45, wall_x - 0.2) <= 19 &&
           CellAt(g, wall_x + 0.5, 0.0) == -1;
  }

  testing::TestDomain domain_;
  ScratchFolder state_dir_;
  sim::WorldMap world_;
  sim::CameraRenderer renderer_;
  std::unique_ptr<bus::Participant> participant_;
  std::unique_ptr<bus::Publisher<msg::Image>> image_pub_;
  std::unique_ptr<bus::Publisher<msg::ExperiencePose>> pose_pub_;
  std::unique_ptr<bus::Publisher<msg::ExperienceMap>> map_pub_;
  std::unique_ptr<bus::Subscriber<msg::ObstacleProfile>> profile_sub_;
  std::unique_ptr<bus::Subscriber<msg::OccupancyGrid>> grid_sub_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> status_sub_;
};

TEST_F(OccupancyServiceTest, ProfileOfEachFrameShowsTheWallAtItsDistance) {
  auto service = Start();
  for (uint64_t seq = 1; seq <= 4; ++seq) {
    const auto profile = SendFrame(seq, /*pose_first=*/seq % 2 == 0);
    ASSERT_TRUE(profile) << "no profile for frame " << seq << "\n" << service->Output();
    EXPECT_EQ(profile->header.robot_id, "robot1");
    EXPECT_EQ(profile->header.stamp_ns, static_cast<int64_t>(seq) * 100'000'000);
    EXPECT_EQ(profile->experience_id, 1u);
    ASSERT_FALSE(profile->bins.empty());
    // The bin looking straight ahead.
    size_t ahead = 0;
    for (size_t i = 0; i < profile->bins.size(); ++i)
      if (std::abs(profile->bearing_min_rad + i * profile->bearing_step_rad) <
          std::abs(profile->bearing_min_rad + ahead * profile->bearing_step_rad))
        ahead = i;
    EXPECT_EQ(profile->bins[ahead].status, msg::ProfileBinStatus::PROFILE_BIN_OBSTACLE);
    EXPECT_NEAR(profile->bins[ahead].range_m, kWallX, 0.05);
  }
}

TEST_F(OccupancyServiceTest, GridHasTheWallOccupiedAndTheFloorBeforeItFree) {
  auto service = Start({"--set", "occupancy.grid_publish_every_n_frames=10"});
  for (uint64_t seq = 1; seq <= 10; ++seq) ASSERT_TRUE(SendFrame(seq)) << service->Output();
  const auto grid = AwaitGrid([](const msg::OccupancyGrid&) { return true; });
  ASSERT_TRUE(grid) << service->Output();
  EXPECT_EQ(grid->header.frame_seq, 10u);
  EXPECT_EQ(grid->map_version, 1u);
  EXPECT_EQ(grid->cells.size(), static_cast<size_t>(grid->width) * grid->height);
  EXPECT_GE(MaxAlongX(*grid, kWallX - 0.1, kWallX + 0.1), 65) << "wall not occupied";
  EXPECT_LE(MaxAlongX(*grid, 0.45, kWallX - 0.2), 19) << "floor before the wall not free";
  EXPECT_EQ(CellAt(*grid, kWallX + 0.5, 0.0), -1) << "behind the wall should stay unknown";
}

TEST_F(OccupancyServiceTest, CorrectedExperienceMovesTheOccupiedCells) {
  auto service = Start();
  for (uint64_t seq = 1; seq <= 10; ++seq) ASSERT_TRUE(SendFrame(seq)) << service->Output();
  ASSERT_TRUE(AwaitGrid([](const msg::OccupancyGrid& g) { return ShowsWallAhead(g, kWallX); }))
      << service->Output();

  // Loop closure moved experience 1 (and everything seen from it) half a metre along x.
  map_pub_->Publish(Correction(2, 0.5));

  const auto moved = AwaitGrid([](const msg::OccupancyGrid& g) { return g.map_version == 2; });
  ASSERT_TRUE(moved) << service->Output();
  EXPECT_GE(MaxAlongX(*moved, kWallX + 0.5 - 0.1, kWallX + 0.5 + 0.1), 65) << "wall not at its corrected place";
  EXPECT_LE(MaxAlongX(*moved, kWallX - 0.1, kWallX + 0.1), 19) << "old wall position should now be free floor";
}

TEST_F(OccupancyServiceTest, ARebuildAlignsFramesTheMapPutOffTheWallSeenBefore) {
  for (const bool align : {false, true}) {
    std::vector<std::string> args;
    if (align) args = {"--set", "occupancy.profile_alignment.window_m=0.3"};
    auto service = Start(args);
    for (uint64_t seq = 1; seq <= 10; ++seq) ASSERT_TRUE(SendFrame(seq)) << service->Output();
    // The robot is back where it was, but the map puts it 0.2 m short: the wall it sees is drawn
    // 0.2 m in front of the wall, on floor seen free ten times.
    for (uint64_t seq = 11; seq <= 20; ++seq) ASSERT_TRUE(SendFrame(seq, true, 1, -0.2)) << service->Output();
    // A correction (the experience moves 1 cm) rebuilds the grid. (The second service gets the
    // first one's map as a late joiner: a newer version.)
    const uint64_t version = align ? 3 : 2;
    map_pub_->Publish(Correction(version, 0.01));
    const auto rebuilt = AwaitGrid([&](const msg::OccupancyGrid& g) { return g.map_version == version; });
    ASSERT_TRUE(rebuilt) << service->Output();
    EXPECT_GE(MaxAlongX(*rebuilt, kWallX - 0.05, kWallX + 0.1), 65) << "the wall";
    if (align) {
      EXPECT_LE(MaxAlongX(*rebuilt, kWallX - 0.3, kWallX - 0.1), 19) << "the wall drawn again 0.2 m short";
    } else {
      EXPECT_GE(MaxAlongX(*rebuilt, kWallX - 0.3, kWallX - 0.1), 65) << "the wall drawn again 0.2 m short";
    }
    service->Signal(SIGTERM);
    ASSERT_EQ(service->WaitExit(10s), 0) << service->Output();
    if (align) {
      EXPECT_NE(service->Output().find("10 of 20 kept profiles were aligned"), std::string::npos) << service->Output();
    }
    std::filesystem::remove(state_dir_.path() / "occupancy.pb");
  }
}

TEST_F(OccupancyServiceTest, WhileTheMapKeepsCorrectingItRebuildsAtMostEveryNFrames) {
  auto service = Start({"--set", "occupancy.grid_publish_every_n_frames=1", "--set",
                        "occupancy.rebuild_at_most_every_n_frames=5"});
  for (uint64_t seq = 1; seq <= 10; ++seq) ASSERT_TRUE(SendFrame(seq)) << service->Output();
  map_pub_->Publish(Correction(2, 0.5));  // the first correction is applied at once
  ASSERT_TRUE(AwaitGrid([](const msg::OccupancyGrid& g) { return g.map_version == 2; })) << service->Output();
  map_pub_->Publish(Correction(3, 0.0));  // the next one waits for 5 frames since the rebuild
  ASSERT_TRUE(map_pub_->WaitForAcknowledgments(5s));
  for (uint64_t seq = 11; seq <= 13; ++seq) {
    // The poses come from the corrected map already; the grid is not on it until it is rebuilt.
    ASSERT_TRUE(SendFrame(seq, /*pose_first=*/true, /*map_version=*/3)) << service->Output();
    const auto grid = AwaitGrid([seq](const msg::OccupancyGrid& g) { return g.header.frame_seq == seq; });
    ASSERT_TRUE(grid) << service->Output();
    EXPECT_EQ(grid->map_version, 2u) << "after " << seq - 10 << " frames: rebuilt again, or took the poses' version";
  }
  for (uint64_t seq = 14; seq <= 15; ++seq) ASSERT_TRUE(SendFrame(seq, true, 3)) << service->Output();
  const auto rebuilt = AwaitGrid([](const msg::OccupancyGrid& g) { return g.map_version == 3; });
  ASSERT_TRUE(rebuilt) << service->Output();
  EXPECT_EQ(rebuilt->header.frame_seq, 15u);
  EXPECT_TRUE(ShowsWallAhead(*rebuilt, kWallX)) << "the wall is back where the experience went back";
}

TEST_F(OccupancyServiceTest, TheCorrectionStillWaitingAtSigtermIsInTheGridItPublishesAndSaves) {
  // Rebuilds spaced far apart, by frames or by the rebuild thread's share of the time (a millionth:
  // a rebuild of a millisecond holds the next for over a quarter of an hour): the second
  // correction is still waiting when the service stops.
  const std::vector<std::vector<std::string>> spacings{
      {"--set", "occupancy.rebuild_at_most_every_n_frames=1000"},
      {"--set", "occupancy.rebuild_at_most_every_n_frames=0", "--set", "occupancy.rebuild_max_busy_share=0.000001"}};
  uint64_t version = 1;
  for (const auto& spacing : spacings) {
    std::vector<std::string> args = spacing;
    args.insert(args.end(), {"--set", "occupancy.grid_publish_every_n_frames=1"});
    auto service = Start(args);
    for (uint64_t seq = 1; seq <= 10; ++seq) ASSERT_TRUE(SendFrame(seq)) << service->Output();
    const uint64_t first = ++version, second = ++version;  // the second service gets the first's map as a late joiner
    map_pub_->Publish(Correction(first, 0.5));  // the first correction is applied at once
    ASSERT_TRUE(AwaitGrid([&](const msg::OccupancyGrid& g) { return g.map_version == first; })) << service->Output();
    map_pub_->Publish(Correction(second, 0.0));  // the experience back where it was: the wall at 1 m again
    ASSERT_TRUE(map_pub_->WaitForAcknowledgments(5s));
    for (uint64_t seq = 11; seq <= 13; ++seq) {  // frames flow; the grid stays on the first correction
      ASSERT_TRUE(SendFrame(seq, true, second)) << service->Output();
      const auto grid = AwaitGrid([seq](const msg::OccupancyGrid& g) { return g.header.frame_seq == seq; });
      ASSERT_TRUE(grid) << service->Output();
      EXPECT_EQ(grid->map_version, first) << spacing.back();
    }
    service->Signal(SIGTERM);
    const auto last = AwaitGrid([&](const msg::OccupancyGrid& g) { return g.map_version == second; });
    ASSERT_EQ(service->WaitExit(10s), 0) << service->Output();
    ASSERT_TRUE(last) << "no grid of the last correction published on the way out\n" << service->Output();
    EXPECT_TRUE(ShowsWallAhead(*last, kWallX));

    const sim::WorldMap saved = sim::WorldMap::LoadFromYaml((state_dir_.path() / "grid.yaml").string());
    const auto at = [&saved](double x) { return saved.Classify(saved.WorldToCell({x, 0.0})); };
    // The cell just behind the wall's face, which lies on a cell border (5-cm cells): all wall.
    EXPECT_EQ(at(kWallX + 0.025), sim::CellClass::kOccupied) << "the exported grid's wall is not at 1 m";
    EXPECT_EQ(at(kWallX + 0.475), sim::CellClass::kUnknown) << "the exported grid still has the wall at 1.5 m";
    EXPECT_EQ(at(kWallX - 0.4), sim::CellClass::kFree);
    std::filesystem::remove(state_dir_.path() / "occupancy.pb");
  }
}

// A service whose rebuilds take seconds: a 2-m, 1-rad alignment search for each of `misplaced`
// frames the map put 0.2 m short of where ten frames saw the wall (no periodic save). Waits until
// the service has taken all its frames.
class SlowRebuildTest : public OccupancyServiceTest {
 protected:
  static constexpr int kTrueFrames = 10, kMisplacedFrames = 20;
  static constexpr int kProfiles = kTrueFrames + kMisplacedFrames;

  std::unique_ptr<ChildProcess> StartWithFrames(const std::vector<std::string>& extra) {
    std::vector<std::string> args{"--set", "occupancy.profile_alignment.window_m=2", "--set",
                                  "occupancy.profile_alignment.window_rad=1", "--set", "service.state_save_period_s=3600"};
    args.insert(args.end(), extra.begin(), extra.end());
    auto service = Start(args);
    for (uint64_t seq = 1; seq <= kProfiles; ++seq) {
      EXPECT_TRUE(SendFrame(seq, true, 1, seq <= kTrueFrames ? 0.0 : -0.2)) << service->Output();
    }
    return service;
  }

  // Publishes a correction and waits until the service has received it (its heartbeat counts
  // `inputs` messages in: two for each frame, one for each correction).
  void Correct(uint64_t version, double experience_x, uint64_t inputs, ChildProcess& service) {
    map_pub_->Publish(Correction(version, experience_x));
    ASSERT_TRUE(AwaitStatus([inputs](const msg::ServiceStatus& s) { return s.messages_in >= inputs; }))
        << service.Output();
  }

  int SavedProfiles() {
    occupancy::proto::OccupancyState state;
    ReadStateFile(state_dir_.path() / "occupancy.pb", "rslam.occupancy.OccupancyState", 1, state);
    return state.profiles_size();
  }
};

TEST_F(SlowRebuildTest, AStopItsDeadlineEndsInTheLastRebuildHasSavedEveryProfileFirst) {
  auto service = StartWithFrames({"--set", "service.stop_timeout_s=0.5"});
  Correct(2, 0.5, 2 * kProfiles + 1, *service);  // a rebuild starts at once and takes seconds
  service->Signal(SIGTERM);
  ASSERT_EQ(service->WaitExit(10s), std::optional<int>(0)) << service->Output();
  ASSERT_NE(service->Output().find("the stop did not finish within 500 ms"), std::string::npos)
      << "the rebuild was not still under way when the deadline came\n" << service->Output();
  EXPECT_EQ(SavedProfiles(), kProfiles) << service->Output();
}

TEST_F(SlowRebuildTest, AtTheStopARebuildOfAnOlderMapIsDroppedForTheNewestOne) {
  auto service = StartWithFrames({"--set", "occupancy.rebuild_at_most_every_n_frames=1000", "--set",
                                   "service.stop_timeout_s=30"});
  Correct(2, 0.5, 2 * kProfiles + 1, *service);  // rebuilt at once, for seconds
  Correct(3, 0.0, 2 * kProfiles + 2, *service);  // waits for that rebuild (and for 1000 frames)
  service->Signal(SIGTERM);
  const auto last = AwaitGrid([](const msg::OccupancyGrid& g) { return g.map_version >= 2; }, 30s);
  ASSERT_EQ(service->WaitExit(30s), std::optional<int>(0)) << service->Output();
  ASSERT_TRUE(last) << service->Output();
  EXPECT_EQ(last->map_version, 3u) << "the grid of the older map was finished and published first";
  EXPECT_TRUE(ShowsWallAhead(*last, kWallX)) << "the experience is back at the origin: the wall at 1 m";
  EXPECT_NE(service->Output().find("map version 2: rebuild dropped for map version 3"), std::string::npos)
      << service->Output();
  EXPECT_EQ(service->Output().find("map version 2: rebuilt"), std::string::npos) << service->Output();
  EXPECT_EQ(SavedProfiles(), kProfiles);
}

TEST_F(OccupancyServiceTest, AcceptsMonoImages) {
  auto service = Start();
  const cv::Mat bgr = renderer_.Render(Pose2D{}, 1);
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  msg::Image image;
  image.header = {"robot1", 1, 100'000'000};
  image.width = static_cast<uint32_t>(grey.cols);
  image.height = static_cast<uint32_t>(grey.rows);
  image.encoding = "mono8";
  image.step = static_cast<uint32_t>(grey.cols);
  image.data.assign(grey.data, grey.data + grey.total());
  std::optional<msg::ObstacleProfile> profile;
  // Sent again until a profile comes: images are best effort, and the service's readers may match
  // ours a little after ours matched theirs.
  ASSERT_TRUE(WaitFor(
      [&] {
        pose_pub_->Publish(Pose(1, 0, 0, 0));
        image_pub_->Publish(image);
        profile = profile_sub_->TakeOne(200ms);
        return profile.has_value();
      },
      10s))
      << service->Output();
  EXPECT_EQ(profile->header.frame_seq, 1u);
  EXPECT_FALSE(profile->bins.empty());
}

TEST_F(OccupancyServiceTest, MalformedInputIsCountedAndTheServiceKeepsWorking) {
  auto service = Start();
  ASSERT_TRUE(SendFrame(1)) << service->Output();

  msg::Image good = Frame(2, Pose2D{});
  msg::Image short_data = good;
  short_data.data.resize(good.data.size() / 2);
  msg::Image unknown_encoding = good;
  unknown_encoding.encoding = "rgb16";
  msg::Image huge = good;
  huge.width = 100000;
  huge.height = 100000;
  huge.step = 300000;
  msg::Image wrong_size = Frame(2, Pose2D{});
  wrong_size.width = 160;
  wrong_size.step = 480;
  msg::ExperiencePose nan_pose = Pose(2, std::numeric_limits<double>::quiet_NaN(), 0, 0);
  for (const msg::Image* bad : {&short_data, &unknown_encoding, &huge, &wrong_size}) image_pub_->Publish(*bad);
  pose_pub_->Publish(nan_pose);

  EXPECT_TRUE(service->Running());
  const auto profile = SendFrame(3);
  ASSERT_TRUE(profile) << "no answer to a good frame after bad ones\n" << service->Output();
  const auto status = AwaitStatus([](const msg::ServiceStatus& s) { return s.messages_rejected >= 5; });
  ASSERT_TRUE(status) << service->Output();
  EXPECT_EQ(status->state, "running");
}

TEST_F(OccupancyServiceTest, SigtermSavesStateAndExportsTheGrid) {
  {
    auto service = Start();
    for (uint64_t seq = 1; seq <= 10; ++seq) ASSERT_TRUE(SendFrame(seq)) << service->Output();
    service->Signal(SIGTERM);
    ASSERT_EQ(service->WaitExit(10s), 0) << service->Output();
  }
  const auto dir = state_dir_.path();
  EXPECT_TRUE(std::filesystem::exists(dir / "occupancy.pb"));
  EXPECT_TRUE(std::filesystem::exists(dir / "grid.pgm"));
  EXPECT_TRUE(std::filesystem::exists(dir / "grid.yaml"));
  EXPECT_TRUE(std::filesystem::exists(dir / "occupancy.png"));

  // Restarted, it shows the restored grid at once, without any new frame.
  auto restarted = Start();
  EXPECT_TRUE(AwaitGrid([](const msg::OccupancyGrid& g) { return ShowsWallAhead(g, kWallX); }))
      << restarted->Output();
}

TEST_F(OccupancyServiceTest, FramesThatShowNothingNewArePublishedButNotKept) {
  // Ten frames from one pose: each gets its profile; with a spacing, only the first joins the map.
  for (const bool spaced : {false, true}) {
    std::vector<std::string> args;
    if (spaced)
      args = {"--set", "occupancy.profile_min_spacing_m=0.08", "--set", "occupancy.profile_min_turn_rad=0.25"};
    auto service = Start(args);
    for (uint64_t seq = 1; seq <= 10; ++seq) ASSERT_TRUE(SendFrame(seq)) << service->Output();
    service->Signal(SIGTERM);
    ASSERT_EQ(service->WaitExit(10s), 0) << service->Output();
    occupancy::proto::OccupancyState state;
    ReadStateFile(state_dir_.path() / "occupancy.pb", "rslam.occupancy.OccupancyState", 1, state);
    EXPECT_EQ(state.profiles_size(), spaced ? 1 : 10);
    std::filesystem::remove(state_dir_.path() / "occupancy.pb");
  }
}

TEST_F(OccupancyServiceTest, RestartAfterSigkillReloadsTheLastSavedStateAndContinues) {
  const auto state_file = state_dir_.path() / "occupancy.pb";
  {
    auto service = Start();
    for (uint64_t seq = 1; seq <= 10; ++seq) ASSERT_TRUE(SendFrame(seq)) << service->Output();
    const auto after_frames = std::filesystem::file_time_type::clock::now();
    // A periodic save made after the last frame (every 0.3 s here).
    ASSERT_TRUE(WaitFor(
        [&] {
          std::error_code ec;
          return std::filesystem::exists(state_file) && std::filesystem::last_write_time(state_file, ec) > after_frames;
        },
        5s));
    service->Signal(SIGKILL);
    ASSERT_EQ(service->WaitExit(5s), 128 + SIGKILL);
  }
  auto restarted = Start();
  ASSERT_TRUE(AwaitGrid([](const msg::OccupancyGrid& g) { return ShowsWallAhead(g, kWallX); }))
      << restarted->Output();
  // And it goes on mapping.
  const auto profile = SendFrame(11);
  ASSERT_TRUE(profile) << restarted->Output();
  EXPECT_NEAR(profile->bins[profile->bins.size() / 2].range_m, kWallX, 0.1);
}

TEST_F(OccupancyServiceTest, CorruptStateFileIsRefusedWithExitOne) {
  {
    std::ofstream out(state_dir_.path() / "occupancy.pb", std::ios::binary);
    out << "RSLAMPB1 certainly not a state file";
  }
  const auto [code, output] = testing::RunToExit(
      kBinary, {"--domain", std::to_string(domain_.id()), "--state-dir", state_dir_.path().string()});
  EXPECT_EQ(code, 1) << output;
  EXPECT_NE(output.find("occupancy.pb"), std::string::npos) << output;
}

TEST(OccupancyServiceCommandLineTest, HelpListsConfigKeys) {
  const auto [code, output] = testing::RunToExit(kBinary, {"--help"});
  EXPECT_EQ(code, 0) << output;
  for (const char* key : {"occupancy.camera.height_m", "occupancy.camera.tilt_rad", "occupancy.floor_colour_bgr",
                          "occupancy.grid.resolution_m", "occupancy.sensor.reliable_range_m",
                          "occupancy.grid_publish_every_n_frames"})
    EXPECT_NE(output.find(key), std::string::npos) << key;
}

TEST(OccupancyServiceCommandLineTest, BadRebuildShareExitsTwoNamingIt) {
  for (const char* bad : {"0", "1.5", "nan"}) {
    const auto [code, output] =
        testing::RunToExit(kBinary, {"--set", std::string("occupancy.rebuild_max_busy_share=") + bad});
    EXPECT_EQ(code, 2) << bad << ": " << output;
    EXPECT_NE(output.find("rebuild_max_busy_share"), std::string::npos) << output;
  }
}

TEST(OccupancyServiceCommandLineTest, UnknownConfigKeyExitsTwoNamingIt) {
  const auto [code, output] = testing::RunToExit(kBinary, {"--set", "occupancy.unknown_key=1"});
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("occupancy.unknown_key"), std::string::npos) << output;
}

}  // namespace
}  // namespace rslam
