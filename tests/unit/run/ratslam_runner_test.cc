// RatSlamRunner: the four stages per frame on a synthetic loop (synthetic_loop.h).
#include "tools/run/ratslam_runner.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "synthetic_loop.h"
#include "services/experience_map/experience_action_message.h"
#include "services/pose_cells/pose_cell_action_message.h"

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

// The runner converts only the rows the stages' crops cover: every record and the map must be
// exactly those of feeding the whole frame's cv::cvtColor conversion. The frames get per-pixel
// colour noise so the grey conversion really weighs three different channels.
void ExpectColourRunEqualsWholeFrameGreyRun(const RatSlamConfig& config) {
  const SyntheticLoop loop(36);
  RatSlamRunner colour(config), grey(config);
  cv::RNG rng(77);
  for (int i = 0; i < 48; ++i) {
    cv::Mat bgr = loop.Frame(i);
    cv::Mat noise(bgr.size(), CV_8UC3);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 24);
    bgr += noise;
    cv::Mat whole_grey;
    cv::cvtColor(bgr, whole_grey, cv::COLOR_BGR2GRAY);
    const FrameRecord c = colour.ProcessFrame(bgr, i * kPeriodNs);
    const FrameRecord g = grey.ProcessFrame(whole_grey, i * kPeriodNs);
    ASSERT_EQ(c.velocity.vtrans, g.velocity.vtrans) << "frame " << i;
    ASSERT_EQ(c.velocity.vrot, g.velocity.vrot) << "frame " << i;
    ASSERT_EQ(c.velocity.speed_difference, g.velocity.speed_difference) << "frame " << i;
    ASSERT_EQ(c.view.template_id, g.view.template_id) << "frame " << i;
    ASSERT_EQ(c.view.is_new, g.view.is_new) << "frame " << i;
    ASSERT_EQ(c.view.relative_angle_rad, g.view.relative_angle_rad) << "frame " << i;
    ASSERT_EQ(c.view.difference, g.view.difference) << "frame " << i;
    ASSERT_EQ(c.action.kind, g.action.kind) << "frame " << i;
    ASSERT_EQ(c.action.experience_id, g.action.experience_id) << "frame " << i;
  }
  const auto& ec = colour.experience_map().experiences();
  const auto& eg = grey.experience_map().experiences();
  ASSERT_EQ(ec.size(), eg.size());
  for (size_t i = 0; i < ec.size(); ++i) {
    EXPECT_EQ(ec[i].x_m, eg[i].x_m);
    EXPECT_EQ(ec[i].y_m, eg[i].y_m);
    EXPECT_EQ(ec[i].th_rad, eg[i].th_rad);
  }
}

TEST(RatSlamRunner, ColourFramesGiveExactlyTheRecordsOfTheWholeFrameConvertedToGrey) {
  ExpectColourRunEqualsWholeFrameGreyRun(LoopConfig());
}

TEST(RatSlamRunner, CropsToTheImageEdgeGiveExactlyTheRecordsOfTheWholeFrameConvertedToGrey) {
  YAML::Node root = YAML::Load(SyntheticLoop::ConfigYaml());
  root["odometry"]["vtrans_image_y_max"] = -1;  // to the bottom edge
  root["templates"]["image_crop_y_min"] = 0;    // from the top edge
  ExpectColourRunEqualsWholeFrameGreyRun(RatSlamConfigFromYaml(root));
}

TEST(RatSlamRunner, RejectsBadFramesAndStampsWithoutChangingState) {
  const SyntheticLoop loop(36);
  RatSlamRunner runner(LoopConfig());
  runner.ProcessFrame(loop.Frame(0), 0);
  EXPECT_THROW(runner.ProcessFrame(cv::Mat(), kPeriodNs), std::invalid_argument);
  EXPECT_THROW(runner.ProcessFrame(cv::Mat(480, 640, CV_16UC1, cv::Scalar(0)), kPeriodNs), std::invalid_argument);
  EXPECT_THROW(runner.ProcessFrame(cv::Mat(480, 640, CV_8UC2, cv::Scalar(0)), kPeriodNs), std::invalid_argument);
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
  EXPECT_THROW(runner.IntegrateMeasurements(v, 0.1, templates::ViewMatch{25, false, 0.0, 0.0}), std::invalid_argument);
}

TEST(RatSlamRunner, AGapBeyondMaxFrameGapRestartsTheOdometryAsTheServiceDoes) {
  RatSlamConfig config = LoopConfig();
  config.odometry.max_frame_gap_s = 1.0;
  RatSlamRunner runner(config);
  const SyntheticLoop loop(36);
  runner.ProcessFrame(loop.Frame(0), 0);
  EXPECT_GT(runner.ProcessFrame(loop.Frame(1), kPeriodNs).velocity.vrot, 0.0);
  const FrameRecord after_gap = runner.ProcessFrame(loop.Frame(2), kPeriodNs + 2'000'000'000);
  EXPECT_EQ(after_gap.dt_s, 0.0);
  EXPECT_EQ(after_gap.velocity.vtrans, 0.0);
  EXPECT_EQ(after_gap.velocity.vrot, 0.0);
  EXPECT_GT(runner.ProcessFrame(loop.Frame(3), 2 * kPeriodNs + 2'000'000'000).velocity.vrot, 0.0)
      << "the next frame measures motion again";
}

TEST(RatSlamRunner, OdometryThePoseCellServiceWouldRefuseMovesNothing) {
  RatSlamConfig config = LoopConfig();
  config.pose_cells.max_vrot_radps = 0.5;  // the loop turns at 10 degrees per 0.1 s = 1.75 rad/s
  RatSlamRunner runner(config);
  const SyntheticLoop loop(36);
  for (int i = 0; i < 10; ++i) runner.ProcessFrame(loop.Frame(i), i * kPeriodNs);
  EXPECT_EQ(runner.refused_velocities(), 9u);
  EXPECT_EQ(runner.refused_actions(), 0u);
  // No motion reached the map: every experience is where the first one is.
  for (const auto& e : runner.experience_map().experiences()) {
    EXPECT_EQ(e.x_m, 0.0);
    EXPECT_EQ(e.y_m, 0.0);
  }
}

TEST(ServiceMessages, ActionsTravelAsTheServicesSendThem) {
  pose_cells::Action action;
  action.kind = pose_cells::Action::Kind::kLink;
  action.experience_id = 3;
  action.from_experience_id = 9;
  action.template_id = 2;
  action.pc_x = 1.23456789012345;
  action.pc_y = 20.5;
  action.pc_th = 35.1;
  action.relative_angle_rad = 0.25;
  const msg::PoseCellAction message = pose_cells::ToActionMessage(action, 41, 1.5, -0.2, 0.1);
  EXPECT_EQ(message.kind, msg::ActionKind::ACTION_LINK);
  EXPECT_EQ(message.action_seq, 41u);
  EXPECT_EQ(message.vtrans_mps, 1.5);
  EXPECT_EQ(message.dt_s, 0.1);
  const experience_map::ExperienceAction applied = experience_map::FromActionMessage(message);
  EXPECT_EQ(applied.kind, experience_map::ExperienceAction::Kind::kLink);
  EXPECT_EQ(applied.experience_id, 3u);
  EXPECT_EQ(applied.from_experience_id, 9u);
  EXPECT_EQ(applied.template_id, 2u);
  EXPECT_EQ(applied.sequence, 41u) << "the message counter, as the experience-map service uses";
  EXPECT_EQ(applied.pc_x, static_cast<double>(static_cast<float>(action.pc_x))) << "float on the wire";
  EXPECT_NE(applied.pc_x, action.pc_x);
  // The view: what the templates service sends, and the runner hands the pose cells.
  const double inf = std::numeric_limits<double>::infinity();
  const templates::ViewMatch first = templates::AsPublished({0, true, inf, inf});
  EXPECT_EQ(first.relative_angle_rad, 0.0);
  EXPECT_EQ(first.difference, templates::kNoTemplateDifference);
  const templates::ViewMatch seen = templates::AsPublished({7, false, -0.5, 0.25});
  EXPECT_EQ(seen.template_id, 7u);
  EXPECT_FALSE(seen.is_new);
  EXPECT_EQ(seen.relative_angle_rad, -0.5);
  EXPECT_EQ(seen.difference, 0.25);
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
  // The services' own keys are keys of the same sections.
  const RatSlamConfig node_keys =
      RatSlamConfigFromYaml(YAML::Load("odometry:\n  max_frame_gap_s: 30\npose_cells:\n  join_window_frames: 5\n"));
  EXPECT_EQ(node_keys.odometry.max_frame_gap_s, 30.0);
}

TEST(RatSlamConfig, CameraPreparationTheRunnerDoesNotApplyIsRefused) {
  EXPECT_NO_THROW(RatSlamConfigFromYaml(YAML::Load("camera:\n  grey: true\n  fps: 10\n")));
  EXPECT_NO_THROW(RatSlamConfigFromYaml(YAML::Load("camera:\n  crop: {x: 0, y: 0, width: 0, height: 0}\n")));
  try {
    RatSlamConfigFromYaml(YAML::Load("camera:\n  undistort: true\n"));
    FAIL() << "undistortion accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "camera.undistort");
  }
  try {
    RatSlamConfigFromYaml(YAML::Load("camera:\n  crop: {x: 0, y: 20}\n"));
    FAIL() << "crop accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "camera.crop.y");
  }
}

TEST(RatSlamConfig, ConfigFileOverPresetThenOverrides) {
  YAML::Node base = YAML::Load("templates:\n  match_threshold: 0.1\n  shift_match: 3\n");
  MergeYaml(base, YAML::Load("templates:\n  shift_match: 4\nodometry:\n  camera_hz: 5\n"));
  const RatSlamConfig config = RatSlamConfigFromYaml(base);
  EXPECT_EQ(config.templates.library.match_threshold, 0.1);
  EXPECT_EQ(config.templates.library.shift_match, 4);
  EXPECT_EQ(config.odometry.visual.camera_hz, 5.0);
}

}  // namespace
}  // namespace rslam::run
