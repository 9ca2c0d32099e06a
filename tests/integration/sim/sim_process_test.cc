// rslam-sim as a black box on a private domain: it publishes camera frames, ground truth and
// wheel odometry, executes motion commands with feedback, stops on STOP, and rejects (and counts)
// a malformed command.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/bus/publisher.h"
#include "common/bus/subscriber.h"
#include "tests/support/child_process.h"
#include "tests/support/test_domain.h"

namespace rslam::sim {
namespace {

using namespace std::chrono_literals;

const std::string kSim = RSLAM_BINARY_DIR "/bin/rslam-sim";
using testing::ChildProcess;
using testing::WaitFor;

class SimProcessTest : public ::testing::Test {
 protected:
  void SetUp() override {
    bus::BusConfig config;
    config.domain_id = domain_.id();
    config.robot_id = "robot1";
    participant_ = bus::Participant::Create(config);
    camera_ = std::make_unique<bus::Subscriber<msg::Image>>(*participant_, bus::topics::kSimCamera);
    truth_ = std::make_unique<bus::Subscriber<msg::GroundTruthPose>>(*participant_, bus::topics::kGroundTruth);
    wheel_ = std::make_unique<bus::Subscriber<msg::Velocity>>(*participant_, bus::topics::kWheelOdometry);
    feedback_ = std::make_unique<bus::Subscriber<msg::MotionFeedback>>(*participant_, bus::topics::kMotionFeedback);
    status_ = std::make_unique<bus::Subscriber<msg::ServiceStatus>>(*participant_, bus::topics::kStatus);
    commands_ = std::make_unique<bus::Publisher<msg::MotionCommand>>(*participant_, bus::topics::kExplorerCommand);
  }

  std::vector<std::string> SimArgs() const {
    // A fixed fast rate (no lockstep: no pipeline here); no wait for a camera service.
    return {"--domain", std::to_string(domain_.id()), "--set", "sim.rate_hz=100", "--set",
            "sim.wait_for_pipeline_s=0", "--set", "sim.camera.width=160", "--set", "sim.camera.height=120"};
  }

  // Drains the ground-truth topic; returns the newest pose seen (keeps the previous one if none).
  msg::GroundTruthPose LatestTruth() {
    for (auto& t : truth_->Take()) latest_truth_ = t;
    return latest_truth_;
  }

  void Send(uint64_t seq, msg::MotionKind kind, double angle, double distance) {
    msg::MotionCommand c;
    c.header.robot_id = "robot1";
    c.command_seq = seq;
    c.kind = kind;
    c.angle_rad = angle;
    c.distance_m = distance;
    commands_->Publish(c);
  }

  // Waits for feedback on command seq in the given state; collects everything seen.
  bool AwaitFeedback(uint64_t seq, msg::MotionState state, std::chrono::milliseconds timeout) {
    return WaitFor(
        [&] {
          for (auto& f : feedback_->Take()) feedback_seen_.push_back(f);
          for (const auto& f : feedback_seen_)
            if (f.command_seq == seq && f.state == state) return true;
          return false;
        },
        timeout);
  }

  testing::TestDomain domain_;
  std::unique_ptr<bus::Participant> participant_;
  std::unique_ptr<bus::Subscriber<msg::Image>> camera_;
  std::unique_ptr<bus::Subscriber<msg::GroundTruthPose>> truth_;
  std::unique_ptr<bus::Subscriber<msg::Velocity>> wheel_;
  std::unique_ptr<bus::Subscriber<msg::MotionFeedback>> feedback_;
  std::unique_ptr<bus::Subscriber<msg::ServiceStatus>> status_;
  std::unique_ptr<bus::Publisher<msg::MotionCommand>> commands_;
  msg::GroundTruthPose latest_truth_;
  std::vector<msg::MotionFeedback> feedback_seen_;
};

TEST_F(SimProcessTest, PublishesFramesWithGroundTruthAndWheelOdometryOfTheSameFrame) {
  ChildProcess sim(kSim, SimArgs());
  const auto image = camera_->TakeOne(15s);
  ASSERT_TRUE(image.has_value()) << sim.Output();
  EXPECT_EQ(image->encoding, "bgr8");
  EXPECT_EQ(image->width, 160u);
  EXPECT_EQ(image->height, 120u);
  EXPECT_EQ(image->data.size(), static_cast<size_t>(image->step) * image->height);
  EXPECT_EQ(image->header.robot_id, "robot1");
  // Ground truth and wheel odometry of the same frame carry the same header.
  std::optional<msg::GroundTruthPose> truth;
  ASSERT_TRUE(WaitFor(
      [&] {
        for (auto& t : truth_->Take())
          if (t.header.frame_seq == image->header.frame_seq) truth = t;
        return truth.has_value();
      },
      5s));
  EXPECT_EQ(truth->header, image->header);
  std::optional<msg::Velocity> wheel;
  ASSERT_TRUE(WaitFor(
      [&] {
        for (auto& w : wheel_->Take())
          if (w.header.frame_seq == image->header.frame_seq) wheel = w;
        return wheel.has_value();
      },
      5s));
  EXPECT_EQ(wheel->header, image->header);
  EXPECT_EQ(wheel->source, msg::VelocitySource::VELOCITY_WHEEL);
  EXPECT_GT(wheel->dt_s, 0.0);
  // Stamps are simulated time: frame N + 1 is one time step (0.1 s) after frame N.
  const auto next = camera_->TakeOne(5s);
  ASSERT_TRUE(next.has_value());
  const uint64_t frames = next->header.frame_seq - image->header.frame_seq;
  ASSERT_GT(frames, 0u);
  EXPECT_EQ(next->header.stamp_ns - image->header.stamp_ns, static_cast<int64_t>(frames) * 100'000'000);
}

TEST_F(SimProcessTest, MoveCommandAdvancesTheRobotAndReportsExecutingThenDone) {
  ChildProcess sim(kSim, SimArgs());
  ASSERT_TRUE(commands_->WaitForSubscribers(1, 15s)) << sim.Output();
  ASSERT_TRUE(WaitFor([&] { return LatestTruth().header.frame_seq > 0; }, 10s)) << sim.Output();
  const msg::GroundTruthPose before = LatestTruth();
  Send(1, msg::MotionKind::MOTION_MOVE, 0.0, 0.5);  // the default start is far from every wall
  ASSERT_TRUE(AwaitFeedback(1, msg::MotionState::MOTION_DONE, 10s)) << sim.Output();
  // EXECUTING came first, once.
  int executing = 0;
  for (const auto& f : feedback_seen_) executing += f.command_seq == 1 && f.state == msg::MotionState::MOTION_EXECUTING;
  EXPECT_EQ(executing, 1);
  EXPECT_EQ(feedback_seen_.front().state, msg::MotionState::MOTION_EXECUTING);
  std::this_thread::sleep_for(100ms);  // let the frame that finished the move arrive
  const msg::GroundTruthPose after = LatestTruth();
  EXPECT_NEAR(std::hypot(after.x_m - before.x_m, after.y_m - before.y_m), 0.5, 0.02);
  EXPECT_NEAR(std::remainder(after.theta_rad - before.theta_rad, 2 * M_PI), 0.0, 1e-6);
  // Straight ahead: along the start heading.
  EXPECT_NEAR(std::atan2(after.y_m - before.y_m, after.x_m - before.x_m), before.theta_rad, 0.01);
}

TEST_F(SimProcessTest, StopEndsARunningTurn) {
  ChildProcess sim(kSim, SimArgs());
  ASSERT_TRUE(commands_->WaitForSubscribers(1, 15s)) << sim.Output();
  ASSERT_TRUE(WaitFor([&] { return LatestTruth().header.frame_seq > 0; }, 10s)) << sim.Output();
  const double start_theta = LatestTruth().theta_rad;
  Send(1, msg::MotionKind::MOTION_ROTATE, 6.0, 0.0);  // 7.5 s of simulated turning at 0.8 rad/s
  ASSERT_TRUE(AwaitFeedback(1, msg::MotionState::MOTION_EXECUTING, 10s));
  Send(2, msg::MotionKind::MOTION_STOP, 0.0, 0.0);
  ASSERT_TRUE(AwaitFeedback(2, msg::MotionState::MOTION_DONE, 10s)) << sim.Output();
  std::this_thread::sleep_for(100ms);
  const msg::GroundTruthPose stopped = LatestTruth();
  // Let 20 more frames pass: the robot stays where it stopped.
  ASSERT_TRUE(WaitFor([&] { return LatestTruth().header.frame_seq >= stopped.header.frame_seq + 20; }, 10s));
  EXPECT_DOUBLE_EQ(LatestTruth().theta_rad, stopped.theta_rad);
  EXPECT_GT(std::abs(std::remainder(stopped.theta_rad - start_theta, 2 * M_PI)), 0.0);
  for (const auto& f : feedback_seen_) EXPECT_FALSE(f.command_seq == 1 && f.state == msg::MotionState::MOTION_DONE);
}

TEST_F(SimProcessTest, RejectsAndCountsAMoveWithANaNDistance) {
  ChildProcess sim(kSim, SimArgs());
  ASSERT_TRUE(commands_->WaitForSubscribers(1, 15s)) << sim.Output();
  ASSERT_TRUE(WaitFor([&] { return LatestTruth().header.frame_seq > 0; }, 10s)) << sim.Output();
  const msg::GroundTruthPose before = LatestTruth();
  Send(7, msg::MotionKind::MOTION_MOVE, 0.0, std::numeric_limits<double>::quiet_NaN());
  // The heartbeat (about once a second) counts it as rejected.
  ASSERT_TRUE(WaitFor(
      [&] {
        for (auto& s : status_->Take())
          if (s.service == "sim" && s.messages_rejected >= 1) return true;
        return false;
      },
      10s))
      << sim.Output();
  // No feedback for it, and the robot did not move.
  for (auto& f : feedback_->Take()) EXPECT_NE(f.command_seq, 7u);
  const msg::GroundTruthPose after = LatestTruth();
  EXPECT_GT(after.header.frame_seq, before.header.frame_seq);
  EXPECT_DOUBLE_EQ(after.x_m, before.x_m);
  EXPECT_DOUBLE_EQ(after.y_m, before.y_m);
  // The process keeps running and still obeys a good command afterwards.
  Send(8, msg::MotionKind::MOTION_ROTATE, 0.5, 0.0);
  EXPECT_TRUE(AwaitFeedback(8, msg::MotionState::MOTION_DONE, 10s)) << sim.Output();
  EXPECT_NE(sim.Output().find("rejected command"), std::string::npos);
}

TEST_F(SimProcessTest, ExitsWithCode2OnAMissingWorldFile) {
  std::vector<std::string> args = SimArgs();
  args.insert(args.end(), {"--set", "sim.world_yaml=/nonexistent/world.yaml"});
  ChildProcess sim(kSim, args);
  const auto code = sim.WaitExit(15s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 2) << sim.Output();
  EXPECT_NE(sim.Output().find("world_yaml"), std::string::npos) << sim.Output();
}

TEST_F(SimProcessTest, StopsAfterMaxFrames) {
  std::vector<std::string> args = SimArgs();
  args.insert(args.end(), {"--set", "sim.max_frames=30"});
  ChildProcess sim(kSim, args);
  const auto code = sim.WaitExit(15s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 0) << sim.Output();
}

}  // namespace
}  // namespace rslam::sim
