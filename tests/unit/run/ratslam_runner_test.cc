// RatSlamRunner: the four stages per frame on a synthetic loop (synthetic_loop.h).
#include "tools/run/ratslam_runner.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <stdexcept>

#include "synthetic_loop.h"

namespace rslam::run {
namespace {

using testing::SyntheticLoop;

constexpr int64_t kPeriodNs = 100'000'000;  // 10 Hz

RatSlamConfig LoopConfig() { return RatSlamConfigFromYaml(YAML::Load(SyntheticLoop::ConfigYaml())); }

TEST(RatSlamRunner, FirstFrameHasZeroVelocityAndZeroDtThenOdometryMoves) {
  RatSlamRunner runner(LoopConfig());
  const SyntheticLoop loop(36);
  const FrameRecord first = runner.ProcessFrame(loop.Frame(0), 0);
  EXPECT_EQ(first.dt_s, 0.0);
  EXPECT_EQ(first.velocity.vtrans, 0.0);
  EXPECT_EQ(first.velocity.vrot, 0.0);
  EXPECT_TRUE(first.view.is_new);
  EXPECT_EQ(first.action.kind, pose_cells::Action::Kind::kCreate);
  ASSERT_EQ(runner.experience_map().experiences().size(), 1u);

  const FrameRecord second = runner.ProcessFrame(loop.Frame(1), kPeriodNs);
  EXPECT_DOUBLE_EQ(second.dt_s, 0.1);
  // 20 px of a 640 px, 320 degree view = 10 degrees in 0.1 s, counter-clockwise.
  EXPECT_NEAR(second.velocity.vrot, 10.0 * M_PI / 180.0 / 0.1, 1e-9);
  EXPECT_GT(second.velocity.vtrans, 0.0);
  EXPECT_EQ(second.frame_index, 1u);
  EXPECT_EQ(runner.frames_processed(), 2u);
}

TEST(RatSlamRunner, LearnsTheFirstLapAndRecognisesItOnTheSecondWithALoopClosure) {
  RatSlamRunner runner(LoopConfig());
  const SyntheticLoop loop(36);
  const int n = loop.places_per_lap();
  int frame = 0;
  for (; frame < n; ++frame) runner.ProcessFrame(loop.Frame(frame), frame * kPeriodNs);
  const size_t templates_after_first_lap = runner.templates().size();
  const size_t experiences_after_first_lap = runner.experience_map().experiences().size();
  EXPECT_GE(templates_after_first_lap, static_cast<size_t>(n * 9 / 10)) << "every place looks different";
  EXPECT_EQ(runner.loop_closures(), 0u);

  bool recognised_first_view = false;
  for (; frame < 2 * n + 4; ++frame) {
    const FrameRecord r = runner.ProcessFrame(loop.Frame(frame), frame * kPeriodNs);
    if (frame == n) recognised_first_view = !r.view.is_new && r.view.template_id == 0;
  }
  EXPECT_TRUE(recognised_first_view);
  EXPECT_EQ(runner.templates().size(), templates_after_first_lap) << "the second lap learns nothing";
  EXPECT_GE(runner.loop_closures(), 1u);
  ASSERT_FALSE(runner.loop_closure_links().empty());
  // The closure joins the end of the first lap to its start.
  const auto [from, to] = *runner.loop_closure_links().begin();
  EXPECT_GE(from, experiences_after_first_lap / 2);
  EXPECT_LT(to, experiences_after_first_lap / 4);
  // The second lap mostly reuses places instead of creating new ones.
  EXPECT_LT(runner.experience_map().experiences().size(), experiences_after_first_lap + n / 4);

  const double error_before = runner.RmsLinkError();
  const RelaxResult relax = runner.RelaxToConvergence();
  EXPECT_TRUE(relax.converged);
  EXPECT_GT(relax.sweeps, 0);
  EXPECT_LE(relax.rms_link_error_m, error_before + 1e-9);
}

TEST(RatSlamRunner, SameFramesGiveTheSameMap) {
  const SyntheticLoop loop(36);
  RatSlamRunner a(LoopConfig()), b(LoopConfig());
  for (int i = 0; i < 80; ++i) {
    a.ProcessFrame(loop.Frame(i), i * kPeriodNs);
    b.ProcessFrame(loop.Frame(i), i * kPeriodNs);
  }
  const auto& ea = a.experience_map().experiences();
  const auto& eb = b.experience_map().experiences();
  ASSERT_EQ(ea.size(), eb.size());
  for (size_t i = 0; i < ea.size(); ++i) {
    EXPECT_EQ(ea[i].x_m, eb[i].x_m);
    EXPECT_EQ(ea[i].y_m, eb[i].y_m);
    EXPECT_EQ(ea[i].th_rad, eb[i].th_rad);
    EXPECT_EQ(ea[i].template_id, eb[i].template_id);
  }
}

TEST(RatSlamRunner, GreyAndColourFramesGiveTheSameResult) {
  const SyntheticLoop loop(36);
  RatSlamRunner colour(LoopConfig()), grey(LoopConfig());
  for (int i = 0; i < 12; ++i) {
    const cv::Mat bgr = loop.Frame(i);
    const FrameRecord c = colour.ProcessFrame(bgr, i * kPeriodNs);
    const FrameRecord g = grey.ProcessFrame(ToGrey(bgr), i * kPeriodNs);
    EXPECT_EQ(c.velocity.vtrans, g.velocity.vtrans);
    EXPECT_EQ(c.velocity.vrot, g.velocity.vrot);
    EXPECT_EQ(c.view.template_id, g.view.template_id);
    EXPECT_EQ(c.action.kind, g.action.kind);
  }
}

TEST(RatSlamRunner, RejectsBadFramesAndStampsWithoutChangingState) {
  const SyntheticLoop loop(36);
  RatSlamRunner runner(LoopConfig());
  runner.ProcessFrame(loop.Frame(0), 0);
  EXPECT_THROW(runner.ProcessFrame(cv::Mat(), kPeriodNs), std::invalid_argument);
  EXPECT_THROW(runner.ProcessFrame(cv::Mat(480, 640, CV_16UC1, cv::Scalar(0)), kPeriodNs), std::invalid_argument);
  EXPECT_THROW(runner.ProcessFrame(cv::Mat(480, 640, CV_8UC2, cv::Scalar(0)), kPeriodNs), std::invalid_argument);
  EXPECT_THROW(runner.ProcessFrame(cv::Mat(240, 320, CV_8UC1, cv::Scalar(0)), kPeriodNs), std::invalid_argument)
      << "size change mid-stream";
  EXPECT_THROW(runner.ProcessFrame(loop.Frame(1), 0), std::invalid_argument) << "stamp not after the previous";
  EXPECT_THROW(runner.ProcessFrame(loop.Frame(1), -5), std::invalid_argument);
  EXPECT_EQ(runner.frames_processed(), 1u);
  EXPECT_EQ(runner.templates().size(), 1u);
  // Still usable: the next good frame is frame 1 with dt from frame 0.
  const FrameRecord next = runner.ProcessFrame(loop.Frame(1), kPeriodNs);
  EXPECT_DOUBLE_EQ(next.dt_s, 0.1);
  EXPECT_EQ(next.frame_index, 1u);
}

TEST(RatSlamRunner, PrefilledTemplatesAndMeasurementsBuildAMap) {
  const SyntheticLoop loop(36);
  RatSlamRunner runner(LoopConfig());
  odometry::Velocity v;
  v.vtrans = 10.0;
  v.vrot = 0.3;
  for (int i = 0; i < 20; ++i) {
    const uint32_t id = runner.LearnTemplate(loop.Frame(i));
    runner.IntegrateMeasurements(v, 0.1, templates::ViewMatch{id, true, 0.0, 1.0});
  }
  EXPECT_EQ(runner.templates().size(), 20u);
  EXPECT_EQ(runner.experience_map().experiences().size(), runner.pose_cells().experience_count());
  EXPECT_GE(runner.experience_map().experiences().size(), 20u);
  EXPECT_THROW(runner.IntegrateMeasurements(v, 0.1, templates::ViewMatch{25, false, 0.0, 0.0}),
               std::invalid_argument);
}

TEST(RatSlamConfig, UnknownSectionAndKeyAreNamed) {
  try {
    RatSlamConfigFromYaml(YAML::Load("odometri:\n  camera_hz: 5\n"));
    FAIL() << "unknown section accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "odometri");
  }
  try {
    RatSlamConfigFromYaml(YAML::Load("pose_cells:\n  pc_dim_xyz: 5\n"));
    FAIL() << "unknown key accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "pose_cells.pc_dim_xyz");
  }
  EXPECT_NO_THROW(RatSlamConfigFromYaml(YAML::Load("bus:\n  anything: 1\n"))) << "other services' sections";
}

TEST(RatSlamConfig, ConfigFileOverPresetThenOverrides) {
  YAML::Node base = YAML::Load("templates:\n  match_threshold: 0.1\n  shift_match: 3\n");
  MergeYaml(base, YAML::Load("templates:\n  shift_match: 4\nodometry:\n  camera_hz: 5\n"));
  const RatSlamConfig config = RatSlamConfigFromYaml(base);
  EXPECT_EQ(config.templates.match_threshold, 0.1);
  EXPECT_EQ(config.templates.shift_match, 4);
  EXPECT_EQ(config.odometry.camera_hz, 5.0);
}

}  // namespace
}  // namespace rslam::run
