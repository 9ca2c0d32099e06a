// rslam-odometry as a black box on a private DDS domain: the test plays the camera.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "common/bus/participant.h"
#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "services/occupancy/obstacle_profile_pipeline.h"
#include "services/occupancy/occupancy_node_config.h"
#include "services/odometry/wall_direction.h"
#include "tests/integration/camera/image_test_util.h"
#include "tools/sim/camera_renderer.h"
#include "tools/sim/world_map.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;

const std::string kBinary = RSLAM_BINARY_DIR "/bin/rslam-odometry";
constexpr int kWidth = 160;
constexpr int kHeight = 120;
constexpr double kFovDeg = 60.0;

class OdometryServiceTest : public ::testing::Test {
 protected:
  OdometryServiceTest() {
    bus::BusConfig config;
    config.domain_id = domain_.id();
    participant_ = bus::Participant::Create(config);
    images_ = std::make_unique<bus::Publisher<msg::Image>>(*participant_, bus::topics::kCameraImage);
    wheel_ = std::make_unique<bus::Publisher<msg::Velocity>>(*participant_, bus::topics::kWheelOdometry);
    velocities_ = std::make_unique<bus::Subscriber<msg::Velocity>>(*participant_, bus::topics::kOdometryVelocity);
    heartbeats_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(*participant_, bus::topics::kStatus);
  }

  // Whole-image crops for both profiles, a 60 degree lens, no speed noise floor.
  std::unique_ptr<ChildProcess> Start(std::vector<std::string> extra = {}) {
    std::vector<std::string> args{"--domain", std::to_string(domain_.id()), "--set", "service.heartbeat_period_s=0.2"};
    std::vector<std::string> keys{"vtrans_image_x_min=0", "vtrans_image_x_max=-1", "vtrans_image_y_min=0",
                                  "vtrans_image_y_max=-1", "vrot_image_x_min=0",   "vrot_image_x_max=-1",
                                  "vrot_image_y_min=0",   "vrot_image_y_max=-1",   "camera_fov_deg=60",
                                  "max_shift_px=20"};
    keys.insert(keys.end(), extra.begin(), extra.end());
    for (const auto& k : keys) {
      args.push_back("--set");
      args.push_back("odometry." + k);
    }
    auto process = std::make_unique<ChildProcess>(kBinary, args);
    EXPECT_TRUE(images_->WaitForSubscribers(1, 10s)) << process->Output();
    EXPECT_TRUE(velocities_->WaitForPublishers(1, 10s)) << process->Output();
    return process;
  }

  // The view of a camera at horizontal position x in a wide scene.
  static cv::Mat ViewAt(const cv::Mat& scene, int x) { return scene(cv::Rect(x, 0, kWidth, kHeight)).clone(); }

  // The velocity answering frame `seq`. A frame right after the start can be lost while the
  // service's reader is still matching the test's writer, so an unanswered frame is sent again
  // (a copy that arrives too is refused: its stamp does not increase).
  std::optional<msg::Velocity> Send(const cv::Mat& image, uint64_t seq, int64_t stamp_ns) {
    const msg::Image message = testing::ImageMessage(image, seq, stamp_ns);
    for (int attempt = 0; attempt < 5; ++attempt) {
      images_->Publish(message);
      const auto deadline = std::chrono::steady_clock::now() + 1s;
      while (std::chrono::steady_clock::now() < deadline) {
        const auto v = velocities_->TakeOne(100ms);
        if (v && v->header.frame_seq == seq && v->header.stamp_ns == stamp_ns) return v;
      }
    }
    return std::nullopt;
  }

  testing::TestDomain domain_;
  std::unique_ptr<bus::Participant> participant_;
  std::unique_ptr<bus::Publisher<msg::Image>> images_;
  std::unique_ptr<bus::Publisher<msg::Velocity>> wheel_;
  std::unique_ptr<bus::Subscriber<msg::Velocity>> velocities_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> heartbeats_;
};

TEST_F(OdometryServiceTest, HorizontalShiftGivesRotationOfTheRightSignAndSize) {
  auto odometry = Start();
  const cv::Mat scene = testing::SmoothTexture(kWidth + 100, kHeight, 7);
  const double rad_per_px = kFovDeg / kWidth * M_PI / 180.0;
  // Frames 0-4: the scene moves 3 px right per frame (camera turning left, counter-clockwise);
  // frames 5-8: 2 px left (turning right). Stamps 0.2 s apart.
  std::vector<int> xs{60, 57, 54, 51, 48, 50, 52, 54, 56};
  for (std::size_t i = 0; i < xs.size(); ++i) {
    const auto v = Send(ViewAt(scene, xs[i]), i, 1'000'000'000LL + static_cast<int64_t>(i) * 200'000'000);
    ASSERT_TRUE(v) << "frame " << i << "\n" << odometry->Output();
    EXPECT_EQ(v->header.frame_seq, i);
    EXPECT_EQ(v->header.robot_id, "robot1");
    EXPECT_EQ(v->source, msg::VelocitySource::VELOCITY_VISUAL);
    if (i == 0) {
      EXPECT_EQ(v->dt_s, 0.0) << "the first frame has no predecessor";
      EXPECT_EQ(v->vrot_radps, 0.0);
      EXPECT_EQ(v->vtrans_mps, 0.0);
      continue;
    }
    EXPECT_NEAR(v->dt_s, 0.2, 1e-12) << "dt from stamps";
    const int scene_shift = xs[i - 1] - xs[i];  // > 0: scene moved towards larger x
    EXPECT_NEAR(v->vrot_radps, scene_shift * rad_per_px / 0.2, 1e-9) << "frame " << i;
  }
}

TEST_F(OdometryServiceTest, IdenticalFramesGiveZeroSpeedAndDtFromIrregularStamps) {
  auto odometry = Start();
  const cv::Mat view = testing::SmoothTexture(kWidth, kHeight, 3);
  const std::vector<int64_t> stamps{0, 100'000'000, 400'000'000, 450'000'000};
  for (std::size_t i = 0; i < stamps.size(); ++i) {
    const auto v = Send(view, i, stamps[i]);
    ASSERT_TRUE(v) << odometry->Output();
    EXPECT_EQ(v->vrot_radps, 0.0);
    EXPECT_NEAR(v->vtrans_mps, 0.0, 1e-9);
    if (i > 0) {
      EXPECT_NEAR(v->dt_s, (stamps[i] - stamps[i - 1]) * 1e-9, 1e-12);
    }
  }
}

TEST_F(OdometryServiceTest, MalformedImagesAreCountedAndAGoodFrameIsStillAnswered) {
  auto odometry = Start();
  const cv::Mat view = testing::SmoothTexture(kWidth, kHeight, 5);
  ASSERT_TRUE(Send(view, 0, 1'000'000'000)) << odometry->Output();

  msg::Image short_step = testing::ImageMessage(view, 1, 1'100'000'000);
  short_step.step = kWidth - 1;
  msg::Image size_mismatch = testing::ImageMessage(view, 2, 1'200'000'000);
  size_mismatch.data.pop_back();
  msg::Image unknown_encoding = testing::ImageMessage(view, 3, 1'300'000'000);
  unknown_encoding.encoding = "yuv422";
  msg::Image huge = testing::ImageMessage(view, 4, 1'400'000'000);
  huge.width = 1u << 30;
  huge.height = 1u << 30;
  huge.step = 1u << 30;
  msg::Image stale = testing::ImageMessage(view, 5, 900'000'000);  // earlier than frame 0
  for (const auto* bad : {&short_step, &size_mismatch, &unknown_encoding, &huge, &stale}) images_->Publish(*bad);

  const auto good = Send(view, 6, 1'600'000'000);
  ASSERT_TRUE(good) << odometry->Output();
  EXPECT_EQ(good->header.frame_seq, 6u) << "the bad frames got no answer";
  EXPECT_NEAR(good->dt_s, 0.6, 1e-12) << "dt from the last accepted frame";
  EXPECT_TRUE(odometry->Running());
  EXPECT_TRUE(testing::AwaitHeartbeat(*heartbeats_, "odometry",
                                      [](const msg::ServiceStatus& s) { return s.messages_rejected >= 5; }, 5s))
      << odometry->Output();
}

TEST_F(OdometryServiceTest, ImageSizeChangeRestartsTheOdometry) {
  auto odometry = Start();
  ASSERT_TRUE(Send(testing::SmoothTexture(kWidth, kHeight, 1), 0, 0)) << odometry->Output();
  const auto resized = Send(testing::SmoothTexture(kWidth + 40, kHeight, 1), 1, 100'000'000);
  ASSERT_TRUE(resized) << odometry->Output();
  EXPECT_EQ(resized->dt_s, 0.0) << "a new image size starts a new run";
  EXPECT_EQ(resized->vrot_radps, 0.0);
  const auto next = Send(testing::SmoothTexture(kWidth + 40, kHeight, 1), 2, 200'000'000);
  ASSERT_TRUE(next) << odometry->Output();
  EXPECT_NEAR(next->dt_s, 0.1, 1e-12);
}

TEST_F(OdometryServiceTest, FrameZeroAfterARestartedCameraStartsANewRun) {
  auto odometry = Start();
  const cv::Mat view = testing::SmoothTexture(kWidth, kHeight, 9);
  ASSERT_TRUE(Send(view, 0, 5'000'000'000)) << odometry->Output();
  ASSERT_TRUE(Send(view, 1, 5'100'000'000)) << odometry->Output();
  // The camera restarts a recording: frame 0 again, stamps from the beginning.
  const auto first = Send(view, 0, 1'000'000'000);
  ASSERT_TRUE(first) << odometry->Output();
  EXPECT_EQ(first->dt_s, 0.0);
  const auto second = Send(view, 1, 1'100'000'000);
  ASSERT_TRUE(second) << odometry->Output();
  EXPECT_EQ(second->header.frame_seq, 1u);
  EXPECT_NEAR(second->dt_s, 0.1, 1e-12);
}

TEST_F(OdometryServiceTest, WheelOdometryIsRepublishedWithItsHeader) {
  auto process = std::make_unique<ChildProcess>(
      kBinary, std::vector<std::string>{"--domain", std::to_string(domain_.id()), "--set",
                                        "odometry.use_wheel_odometry=true"});
  ASSERT_TRUE(wheel_->WaitForSubscribers(1, 10s)) << process->Output();
  ASSERT_TRUE(velocities_->WaitForPublishers(1, 10s)) << process->Output();
  msg::Velocity w;
  w.header = {"robot1", 42, 4'200'000'000};
  w.vtrans_mps = 0.25;
  w.vrot_radps = -0.1;
  w.dt_s = 0.1;
  w.source = msg::VelocitySource::VELOCITY_WHEEL;
  wheel_->Publish(w);
  const auto v = velocities_->TakeOne(5s);
  ASSERT_TRUE(v) << process->Output();
  EXPECT_EQ(*v, w);
  msg::Velocity bad = w;
  bad.vrot_radps = std::nan("");
  wheel_->Publish(bad);
  EXPECT_FALSE(velocities_->TakeOne(500ms)) << "a NaN wheel velocity is not passed on";
}

// Frames the simulator renders in the shipped world, through the demo's config (floor odometry on):
// each velocity says whether its frame showed a straight wall and, if so, the walls' direction
// modulo 90 degrees in the robot frame (the world's walls run along x and y), and carries the
// frame's floor boundary.
TEST_F(OdometryServiceTest, FloorOdometryReportsTheWallsDirectionAndBoundary) {
  const sim::WorldMap world = sim::WorldMap::LoadFromYaml(RSLAM_SOURCE_DIR "/deploy/worlds/uwb-room.yaml");
  sim::CameraRenderer renderer(world, sim::SceneConfig{}, sim::CameraConfig{});
  occupancy::ObstacleProfilePipeline boundary(occupancy::SimulatorMatchedPipelineConfig());
  // Poses whose frames give (in this process) a direction within 0.02 rad of the truth, and poses
  // with nothing within 2 m, from a walk over the map.
  std::vector<std::pair<Pose2D, bool>> poses;
  int with_wall = 0, without = 0;
  uint64_t render_seq = 0;
  for (double x = -6.0; x <= 6.0 && (with_wall < 3 || without < 2); x += 0.5)
    for (double y = -6.0; y <= 6.0; y += 0.5)
      for (double theta = 0.1; theta < 2 * M_PI; theta += 0.7) {
        if (!world.IsDiscFree({x, y}, 0.2)) continue;
        const occupancy::RadialObstacleProfile profile = boundary.ProfileFromImage(renderer.Render({x, y, theta}, render_seq++));
        std::vector<Eigen::Vector2d> points;
        profile.ObstaclePoints(points);
        const auto wall = odometry::WallDirection(points, odometry::WallDirectionConfig{});
        if (wall && with_wall < 3 && std::abs(std::remainder(theta + *wall, M_PI / 2)) < 0.02) {
          poses.push_back({{x, y, theta}, true});
          ++with_wall;
        } else if (points.empty() && without < 2) {
          poses.push_back({{x, y, theta}, false});
          ++without;
        }
      }
  ASSERT_EQ(with_wall, 3);
  ASSERT_EQ(without, 2);

  auto process = std::make_unique<ChildProcess>(
      kBinary, std::vector<std::string>{"--domain", std::to_string(domain_.id()), "--config",
                                        RSLAM_SOURCE_DIR "/deploy/config/demo.yaml"});
  ASSERT_TRUE(images_->WaitForSubscribers(1, 10s)) << process->Output();
  ASSERT_TRUE(velocities_->WaitForPublishers(1, 10s)) << process->Output();
  for (size_t i = 0; i < poses.size(); ++i) {
    const auto& [pose, wall] = poses[i];
    const auto v = Send(renderer.Render(pose, i), i, static_cast<int64_t>(i + 1) * 100'000'000);
    ASSERT_TRUE(v) << process->Output();
    ASSERT_EQ(v->wall_seen, wall) << "frame " << i;
    // The floor boundary goes along (for the pose cells' check): in front, within the 3 m range.
    EXPECT_TRUE(v->boundary_measured);
    for (const msg::FloorPoint& p : v->boundary) {
      EXPECT_GT(p.x_m, 0.0f) << "frame " << i;
      EXPECT_LE(std::hypot(p.x_m, p.y_m), 3.01f) << "frame " << i;
    }
    if (wall) {
      EXPECT_LT(std::abs(std::remainder(pose.theta + v->wall_direction_rad, M_PI / 2)), 0.02) << "frame " << i;
      EXPECT_GE(v->boundary.size(), 8u) << "frame " << i;
    }
  }
}

TEST_F(OdometryServiceTest, BadConfigExitsTwoNamingTheKey) {
  const auto [code, output] = testing::RunToExit(
      kBinary, {"--domain", std::to_string(domain_.id()), "--set", "odometry.max_frame_gap_s=0"});
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("odometry.max_frame_gap_s"), std::string::npos) << output;
}

}  // namespace
}  // namespace rslam
