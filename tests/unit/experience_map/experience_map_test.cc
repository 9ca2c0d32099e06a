// Pins the experience map against paper 000 eqs. 1-3, the budgeted correction's fixed point,
// paths over links, persistence, merging and bad input.
#include "services/experience_map/experience_map.h"
#include "services/experience_map/pose_graph.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>
#include <tuple>
#include <utility>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "common/persistence/state_file.h"

namespace rslam::experience_map {
namespace {

constexpr double kPi = std::numbers::pi;
using Kind = ExperienceAction::Kind;

ExperienceAction Create(uint32_t id, uint32_t from) {
  ExperienceAction a;
  a.kind = Kind::kCreate;
  a.experience_id = id;
  a.from_experience_id = from;
  a.template_id = id;
  return a;
}

ExperienceAction LinkTo(Kind kind, uint32_t from, uint32_t to) {
  ExperienceAction a;
  a.kind = kind;
  a.experience_id = to;
  a.from_experience_id = from;
  return a;
}

// A 10 m square driven in 2 m steps from (0, 0) facing +y (exp_initial_em_deg 90), creating an
// experience per step, turning to the start heading and closing the loop onto experience 0. Odometry is scaled by `scale` and
// turns by `bias` rad per step too much. Returns the true positions of experiences 0..19.
std::vector<std::pair<double, double>> DriveSquare(ExperienceMap& map, double scale, double bias) {
  std::vector<std::pair<double, double>> truth;
  double tx = 0, ty = 0, tth = kPi / 2;
  map.Apply(Create(0, kNoExperience));
  truth.emplace_back(tx, ty);
  uint32_t next = 1;
  for (int side = 0; side < 4; ++side) {
    for (int step = 0; step < 5; ++step) {
      if (step == 0 && side > 0) {
        map.Integrate(0.0, kPi / 2 + bias, 1.0);
        tth += kPi / 2;
      }
      map.Integrate(2.0 * scale, bias, 1.0);
      tx += 2.0 * std::cos(tth);
      ty += 2.0 * std::sin(tth);
      if (side == 3 && step == 4) {
        map.Integrate(0.0, kPi / 2 + bias, 1.0);  // face the way experience 0 was seen
        map.Apply(LinkTo(Kind::kLink, next - 1, 0));
      } else {
        map.Apply(Create(next, next - 1));
        truth.emplace_back(tx, ty);
        ++next;
      }
    }
  }
  return truth;
}

// RMS over all pairs of |distance in the map - true distance| (invariant to rigid motion).
double ShapeError(const ExperienceMap& map, const std::vector<std::pair<double, double>>& truth) {
  double sum = 0;
  int n = 0;
  const auto& e = map.experiences();
  for (size_t i = 0; i < truth.size(); ++i)
    for (size_t j = i + 1; j < truth.size(); ++j) {
      const double dm = std::hypot(e[i].x_m - e[j].x_m, e[i].y_m - e[j].y_m);
      const double dt = std::hypot(truth[i].first - truth[j].first, truth[i].second - truth[j].second);
      sum += (dm - dt) * (dm - dt);
      ++n;
    }
  return std::sqrt(sum / n);
}

ExperienceMapConfig NoCorrection() {
  ExperienceMapConfig c;
  c.exp_relax_budget_links = 0;
  c.exp_loops = 0;
  return c;
}

TEST(ExperienceMap, CreatePlacesExperienceAtAccumulatedOdometryWithEq1Link) {
  ExperienceMap map(NoCorrection());
  map.Apply(Create(0, kNoExperience));
  map.Integrate(1.0, 0.0, 2.0);  // facing +y (90 degrees)
  map.Apply(Create(1, 0));
  ASSERT_EQ(map.experiences().size(), 2u);
  const Experience& e1 = map.experiences()[1];
  EXPECT_NEAR(e1.x_m, 0.0, 1e-12);
  EXPECT_NEAR(e1.y_m, 2.0, 1e-12);
  EXPECT_NEAR(e1.th_rad, kPi / 2, 1e-12);
  ASSERT_EQ(map.links().size(), 1u);
  const Link& l = map.links()[0];
  EXPECT_EQ(l.from_id, 0u);
  EXPECT_EQ(l.to_id, 1u);
  EXPECT_NEAR(l.d_m, 2.0, 1e-12);
  EXPECT_NEAR(l.heading_rad, 0.0, 1e-12);
  EXPECT_NEAR(l.facing_rad, 0.0, 1e-12);
  EXPECT_NEAR(l.travel_time_s, 2.0, 1e-12);
  EXPECT_EQ(map.current_id(), 1u);
  map.Integrate(0.5, 0.0, 1.0);
  EXPECT_NEAR(map.RobotPose().y, 2.5, 1e-12);
}

TEST(ExperienceMap, RepeatedTransitionAveragesLinkByEq2) {
  ExperienceMap map(NoCorrection());
  map.Apply(Create(0, kNoExperience));
  map.Integrate(1.0, 0.0, 2.0);
  map.Apply(Create(1, 0));  // 0 -> 1: d 2, heading 0, facing 0, 2 s
  map.Integrate(1.0, 0.0, 1.0);
  map.Apply(Create(2, 1));
  map.Apply(LinkTo(Kind::kLink, 2, 0));  // back at 0 (teleport: a new link 2 -> 0)
  // Second traversal 0 -> 1: 2.2 m along a direction turned 0.1 rad, in 1 s.
  map.Integrate(2.2, 0.1, 1.0);
  map.Apply(LinkTo(Kind::kSet, 0, 1));
  const Link& l = map.links()[0];
  ASSERT_EQ(l.from_id, 0u);
  ASSERT_EQ(l.to_id, 1u);
  // By hand: mean of (2, 0) and 2.2 (cos 0.1, sin 0.1) = (2.094505, 0.109817).
  EXPECT_NEAR(l.d_m, 2.0973815016852937, 1e-9);
  EXPECT_NEAR(l.heading_rad, 0.05238293398366595, 1e-9);
  EXPECT_NEAR(l.facing_rad, 0.05, 1e-12);
  EXPECT_NEAR(l.travel_time_s, 1.5, 1e-12);
  EXPECT_EQ(l.traversals, 2u);
  EXPECT_EQ(map.links().size(), 3u);  // no duplicate link
}

// Experience 0 faces +y (90 degrees); the robot drives a loop whose dead reckoning comes back
// facing `back_facing` and recognises experience 0 with the view turned `relative` rad.
double HeadingAfterRecognising(double correction, double back_facing, double relative, bool set_view_angle = true) {
  ExperienceMapConfig config = NoCorrection();
  config.exp_heading_correction = correction;
  config.exp_set_view_angle = set_view_angle;
  ExperienceMap map(config);
  map.Apply(Create(0, kNoExperience));
  map.Integrate(1.0, 0.0, 1.0);
  map.Apply(Create(1, 0));
  map.Integrate(0.0, back_facing - kPi / 2, 1.0);
  ExperienceAction back = LinkTo(Kind::kLink, 1, 0);
  back.relative_angle_rad = relative;
  map.Apply(back);
  return map.RobotPose().theta;
}

TEST(ExperienceMap, RecognitionTakesTheConfiguredShareOfTheHeadingDifference) {
  // The recognised heading: experience 0's facing (pi/2) plus the view's offset (0.1).
  EXPECT_NEAR(HeadingAfterRecognising(1.0, kPi / 2 + 0.3, 0.1), kPi / 2 + 0.1, 1e-12);  // OpenRatSLAM
  EXPECT_NEAR(HeadingAfterRecognising(0.0, kPi / 2 + 0.3, 0.1), kPi / 2 + 0.3, 1e-12);  // dead reckoning
  EXPECT_NEAR(HeadingAfterRecognising(0.5, kPi / 2 + 0.3, 0.1), kPi / 2 + 0.2, 1e-12);
  // Across the +-pi seam the blend goes the short way round: halfway between 3.1 and -3.1 is pi.
  EXPECT_NEAR(std::abs(HeadingAfterRecognising(0.5, 3.1, -3.1 - kPi / 2)), kPi, 1e-9);
}

// Driving straight past a wall, each experience made 0.1 m on from the last, the pose cells step
// back to the one before and on again (sets), each view offset read as the same 0.065-rad shift:
// parallax, not a turn. Returns the robot's heading after `steps` such steps and the largest
// facing of any link.
std::pair<double, double> HeadingAfterSetsAlongAWall(bool set_view_angle, int steps) {
  ExperienceMapConfig config = NoCorrection();
  config.exp_heading_correction = 0.3;
  config.exp_set_view_angle = set_view_angle;
  ExperienceMap map(config);
  map.Apply(Create(0, kNoExperience));
  for (uint32_t i = 0; i < static_cast<uint32_t>(steps); ++i) {
    map.Integrate(0.1, 0.0, 1.0);
    map.Apply(Create(i + 1, i));
    for (const auto& [from, to] : {std::pair{i + 1, i}, std::pair{i, i + 1}}) {
      ExperienceAction set = LinkTo(Kind::kSet, from, to);
      set.relative_angle_rad = 0.065;
      map.Apply(set);
    }
  }
  double facing = 0.0;
  for (const Link& l : map.links()) facing = std::max(facing, std::abs(l.facing_rad));
  return {map.RobotPose().theta, facing};
}

TEST(ExperienceMap, ASetTakesTheViewAngleOnlyWhenConfigured) {
  // OpenRatSLAM: every set turns the heading towards the view's 0.065 rad, each new experience
  // is made facing the turned heading, and the re-traversed links' facings take the offset in.
  const auto [turned, turned_link] = HeadingAfterSetsAlongAWall(true, 20);
  EXPECT_GT(turned - kPi / 2, 0.5);
  EXPECT_GT(turned_link, 0.01);
  // Without, nothing turns: the heading and the links' facings stay as the odometry has them.
  const auto [held, held_link] = HeadingAfterSetsAlongAWall(false, 20);
  EXPECT_NEAR(held, kPi / 2, 1e-12);
  EXPECT_NEAR(held_link, 0.0, 1e-12);
  // A recognition that makes a new link still takes the view's angle.
  EXPECT_NEAR(HeadingAfterRecognising(1.0, kPi / 2 + 0.3, 0.1, false), kPi / 2 + 0.1, 1e-12);
}

TEST(ExperienceMap, ALinkToARecognisedPlaceAgreesWithTheHeadingTheRecognitionGives) {
  // Experiences 0, 1 and 2, a metre apart going east, all face east. The robot turns 0.3 rad
  // left at 2 and recognises 0 (a teleport: positions aside) with its view turned 0.3 rad: it
  // faces 0's heading + 0.3, as dead reckoning says, so the new link 2 -> 0 says the two
  // experiences face the same way.
  ExperienceMap map(NoCorrection());
  map.Integrate(0.0, -kPi / 2, 1.0);  // the map starts facing +y: turn east first
  map.Apply(Create(0, kNoExperience));
  map.Integrate(1.0, 0.0, 1.0);
  map.Apply(Create(1, 0));
  map.Integrate(1.0, 0.0, 1.0);
  map.Apply(Create(2, 1));
  ASSERT_NEAR(map.experiences()[0].th_rad, 0.0, 1e-12);
  ASSERT_NEAR(map.experiences()[2].th_rad, 0.0, 1e-12);
  map.Integrate(0.0, 0.3, 1.0);
  ExperienceAction back = LinkTo(Kind::kLink, 2, 0);
  back.relative_angle_rad = 0.3;
  map.Apply(back);
  const Link& link = map.links().back();
  ASSERT_EQ(link.from_id, 2u);
  ASSERT_EQ(link.to_id, 0u);
  EXPECT_NEAR(link.facing_rad, 0.0, 1e-12);  // OpenRatSLAM's sign: 0.6
  EXPECT_NEAR(map.RobotPose().theta, 0.3, 1e-12);
}

// Experience 0 at the origin facing +y, experience 1 two metres east; the robot drives back 1.7
// m west (dead reckoned at x = 0.3, facing -x) and recognises experience 0, measured
// `offset_left_m` to its left (the robot stands at x = -offset_left_m in truth). No map
// correction. Returns the robot's pose after the recognition and the length of the link 0 -> 1,
// averaged with the way back (000 eq. 2).
std::pair<Pose2D, double> RecogniseFromTheEast(double position_correction, double offset_left_m = 0.0) {
  ExperienceMapConfig config = NoCorrection();
  config.exp_position_correction = position_correction;
  ExperienceMap map(config);
  map.Apply(Create(0, kNoExperience));
  map.Integrate(0.0, -kPi / 2, 1.0);  // exp 0 faces +y: turn to +x ...
  map.Integrate(2.0, 0.0, 1.0);       // ... and drive 2 m
  map.Apply(Create(1, 0));
  map.Integrate(0.0, kPi, 1.0);
  map.Integrate(1.7, 0.0, 1.0);
  ExperienceAction link = LinkTo(Kind::kLink, 1, 0);
  link.relative_angle_rad = kPi / 2;  // facing -x, a quarter turn left of experience 0
  link.offset_y_m = offset_left_m;
  map.Apply(link);
  EXPECT_EQ(map.current_id(), 0u);
  EXPECT_EQ(map.links().size(), 1u);
  return {map.RobotPose(), map.links().front().d_m};
}

TEST(ExperienceMap, RecognitionTakesTheConfiguredShareOfThePositionDifference) {
  const Pose2D on = RecogniseFromTheEast(1.0).first;  // OpenRatSLAM: on the experience
  EXPECT_NEAR(on.x, 0.0, 1e-9);
  EXPECT_NEAR(on.y, 0.0, 1e-9);
  const Pose2D part = RecogniseFromTheEast(0.4).first;  // 0.4 of the way from x = 0.3 to 0
  EXPECT_NEAR(part.x, 0.18, 1e-9);
  EXPECT_NEAR(part.y, 0.0, 1e-9);
  ExperienceMapConfig config;
  config.exp_position_correction = 0.0;
  EXPECT_THROW(config.Validate(), ConfigError);
}

// A recognition that measures where the robot stands (the pose cells' exp_boundary_offset) puts
// the robot there, not on the experience, and the way back it observes keeps the true distance.
TEST(ExperienceMap, RecognitionWithAMeasuredOffsetPutsTheRobotWhereItStands) {
  const auto [agrees, agrees_link] = RecogniseFromTheEast(1.0, -0.3);  // at x = 0.3, as dead reckoned
  EXPECT_NEAR(agrees.x, 0.3, 1e-9);
  EXPECT_NEAR(agrees.y, 0.0, 1e-9);
  EXPECT_NEAR(agrees.theta, kPi, 1e-9);
  EXPECT_NEAR(agrees_link, 2.0, 1e-9);
  EXPECT_NEAR(RecogniseFromTheEast(1.0).second, 1.85, 1e-9);  // on the experience: back 0.3 m short
  const Pose2D measured = RecogniseFromTheEast(1.0, -0.1).first;  // at x = 0.1, not 0.3
  EXPECT_NEAR(measured.x, 0.1, 1e-9);
  const Pose2D part = RecogniseFromTheEast(0.4, -0.1).first;  // 0.4 of the way from 0.3 to 0.1
  EXPECT_NEAR(part.x, 0.22, 1e-9);
  EXPECT_NEAR(part.y, 0.0, 1e-9);
}

TEST(ExperienceMap, HeadingCorrectionOutsideZeroToOneIsRefused) {
  ExperienceMapConfig config;
  config.exp_heading_correction = 1.5;
  EXPECT_THROW(config.Validate(), ConfigError);
}

proto::ExperienceMap TwoExperiencesOneMetreOff() {
  proto::ExperienceMap m;
  auto* a = m.add_experiences();
  a->set_x_m(0.0);
  auto* b = m.add_experiences();
  b->set_x_m(3.0);
  auto* l = m.add_links();
  l->set_from_id(0);
  l->set_to_id(1);
  l->set_d_m(2.0);
  l->set_traversals(1);
  m.set_has_current(true);
  m.set_current_id(1);
  return m;
}

TEST(ExperienceMap, CorrectionShrinksLinkErrorByOneMinusTwoAlpha) {
  for (double alpha : {0.5, 0.25, 0.1}) {
    ExperienceMapConfig cfg;
    cfg.exp_correction = alpha;
    ExperienceMap map(cfg);
    map.Load(TwoExperiencesOneMetreOff());
    ASSERT_NEAR(map.MaxLinkError(), 1.0, 1e-12);
    map.Relax(1);
    // 000 eq. 3: each end moves alpha * error towards the other.
    EXPECT_NEAR(map.experiences()[0].x_m, alpha, 1e-12);
    EXPECT_NEAR(map.experiences()[1].x_m, 3.0 - alpha, 1e-12);
    EXPECT_NEAR(map.MaxLinkError(), 1.0 - 2 * alpha, 1e-12) << alpha;
  }
}

TEST(ExperienceMap, DriftedSquareLoopIsCorrectedTowardsTheTrueSquare) {
  // Heading drift is what map correction can undo (a pure scale error keeps every loop
  // consistent, so no correction can see it).
  ExperienceMap uncorrected(NoCorrection());
  const auto truth = DriveSquare(uncorrected, 1.0, 0.03);
  ExperienceMapConfig cfg;
  cfg.exp_relax_budget_links = 0;  // OpenRatSLAM: exp_loops sweeps after every action
  cfg.exp_loops = 100;
  ExperienceMap corrected(cfg);
  DriveSquare(corrected, 1.0, 0.03);
  const double before = ShapeError(uncorrected, truth);
  const double after = ShapeError(corrected, truth);
  EXPECT_GT(before, 1.0);
  EXPECT_LT(after, 0.35 * before) << "before " << before << " after " << after;

  // Least squares (exp_graph_optimisation) with the closure as sure as a step (it is exact here),
  // in the closing frame alone: as good as 100 relaxation sweeps after every action.
  ExperienceMapConfig least_squares_cfg;
  least_squares_cfg.exp_graph_optimisation = true;
  least_squares_cfg.exp_graph_period_frames = 1;
  least_squares_cfg.exp_graph_closure_sigma_m = least_squares_cfg.exp_graph_link_sigma_m;
  least_squares_cfg.exp_graph_closure_sigma_rad = least_squares_cfg.exp_graph_link_sigma_rad;
  ExperienceMap least_squares(least_squares_cfg);
  DriveSquare(least_squares, 1.0, 0.03);
  const double after_least_squares = ShapeError(least_squares, truth);
  EXPECT_LT(after_least_squares, after + 0.005) << "relaxation " << after << " least squares " << after_least_squares;
  EXPECT_EQ(least_squares.experiences()[0].x_m, 0.0);  // the first experience stays put
  EXPECT_EQ(least_squares.experiences()[0].y_m, 0.0);
}

TEST(ExperienceMap, BudgetedCorrectionConvergesToFullRelaxationFixedPoint) {
  ExperienceMap built(NoCorrection());
  DriveSquare(built, 1.05, 0.03);
  const proto::ExperienceMap start = built.Save();

  ExperienceMapConfig full_cfg;
  ExperienceMap full(full_cfg);
  full.Load(start);
  full.Relax(3000);

  ExperienceMapConfig sliced_cfg;
  sliced_cfg.exp_relax_budget_links = 5;  // far less than one sweep (20 links) per frame
  sliced_cfg.exp_local_region_links = 3;
  ExperienceMap sliced(sliced_cfg);
  sliced.Load(start);
  ExperienceMapConfig probe;
  for (int frame = 0; frame < 30000; ++frame) sliced.Apply(ExperienceAction{});

  ASSERT_EQ(sliced.experiences().size(), full.experiences().size());
  for (size_t i = 0; i < full.experiences().size(); ++i) {
    EXPECT_NEAR(sliced.experiences()[i].x_m, full.experiences()[i].x_m, 1e-6) << i;
    EXPECT_NEAR(sliced.experiences()[i].y_m, full.experiences()[i].y_m, 1e-6) << i;
    EXPECT_NEAR(sliced.experiences()[i].th_rad, full.experiences()[i].th_rad, 1e-6) << i;
  }
}

TEST(ExperienceMap, LocalRegionCorrectsALoopClosureWithinAFewFrames) {
  ExperienceMapConfig cfg;
  cfg.exp_relax_budget_links = 100;
  cfg.exp_local_region_links = 50;
  ExperienceMap map(cfg);
  DriveSquare(map, 1.05, 0.03);
  ExperienceMap full(cfg);
  full.Load(map.Save());
  full.Relax(2000);
  ExperienceMap uncorrected(NoCorrection());
  DriveSquare(uncorrected, 1.05, 0.03);
  for (int frame = 0; frame < 20; ++frame) map.Apply(ExperienceAction{});
  // Twenty frames after the closure the map is about as consistent as fully relaxed.
  EXPECT_GT(uncorrected.MaxLinkError(), 3.0);
  EXPECT_LT(map.MaxLinkError(), 1.5 * full.MaxLinkError() + 0.02)
      << map.MaxLinkError() << " vs " << full.MaxLinkError();
}

ExperienceMapConfig LeastSquares(int period_frames) {
  ExperienceMapConfig c;
  c.exp_graph_optimisation = true;
  c.exp_graph_period_frames = period_frames;
  return c;
}

// Where link l says its target is, minus where the target is (m).
double LinkPositionError(const ExperienceMap& map, const Link& l) {
  const Experience& from = map.experiences()[l.from_id];
  const Experience& to = map.experiences()[l.to_id];
  return std::hypot(from.x_m + l.d_m * std::cos(from.th_rad + l.heading_rad) - to.x_m,
                    from.y_m + l.d_m * std::sin(from.th_rad + l.heading_rad) - to.y_m);
}

// A unit square 0 -> 1 -> 2 -> 3 with exact odometric links and a recognition 3 -> 0 that puts
// experience 0 `closure_error` m further along than it is.
proto::ExperienceMap SquareWithAnOffClosure(double closure_error) {
  proto::ExperienceMap m;
  const double xs[] = {0, 1, 1, 0}, ys[] = {0, 0, 1, 1};
  for (int i = 0; i < 4; ++i) {
    auto* e = m.add_experiences();
    e->set_x_m(xs[i]);
    e->set_y_m(ys[i]);
    e->set_th_rad(i * kPi / 2);
  }
  for (uint32_t i = 0; i < 4; ++i) {
    auto* l = m.add_links();
    l->set_from_id(i);
    l->set_to_id((i + 1) % 4);
    l->set_d_m(i == 3 ? 1.0 + closure_error : 1.0);
    l->set_facing_rad(kPi / 2);
    l->set_traversals(1);
    l->set_closes_loop(i == 3);
  }
  m.set_has_current(true);
  m.set_current_id(3);
  return m;
}

// exp_bridge_recognitions. Experiences 0, 1, 2 a metre apart along +x; from 2 the robot drives on
// 0.5 m and sees experience 0 again (a lookalike: it truly stands 2.5 m from 0), which puts it on 0
// and turns its facing by 0.2 rad; then it turns 0.3 rad, drives 0.5 m and makes experience 3.
// Returns the map after the least-squares correction.
std::unique_ptr<ExperienceMap> RecogniseALookalikeThenCreate(bool bridge) {
  ExperienceMapConfig config = LeastSquares(1);
  config.exp_bridge_recognitions = bridge;
  auto map = std::make_unique<ExperienceMap>(config);
  map->Apply(Create(0, kNoExperience));
  map->Integrate(0.0, -kPi / 2, 1.0);  // exp 0 faces +y: turn to +x
  map->Integrate(1.0, 0.0, 1.0);
  map->Apply(Create(1, 0));
  map->Integrate(1.0, 0.0, 1.0);
  map->Apply(Create(2, 1));
  map->Integrate(0.5, 0.0, 1.0);
  ExperienceAction lookalike = LinkTo(Kind::kLink, 2, 0);
  lookalike.relative_angle_rad = -kPi / 2 + 0.2;
  map->Apply(lookalike);
  map->Integrate(0.0, 0.3, 1.0);
  map->Integrate(0.5, 0.0, 1.0);
  map->Apply(Create(3, 0));
  map->OptimiseGraph(10);
  return map;
}

// The experience made after a recognition is linked by the odometry from the one made before it,
// so a recognition's placement is held as loosely as a recognition, not as firmly as odometry.
TEST(ExperienceMap, AfterARecognitionTheNextExperienceIsBridgedByOdometryFromTheLastOneMade) {
  const auto bridged = RecogniseALookalikeThenCreate(true);
  ASSERT_EQ(bridged->experiences().size(), 4u);
  const Link& bridge = bridged->links().back();
  EXPECT_EQ(bridge.from_id, 2u);
  EXPECT_EQ(bridge.to_id, 3u);
  EXPECT_FALSE(bridge.closes_loop);
  // Odometry alone: 0.5 m ahead, then 0.5 m at 0.3 rad; the recognition's 0.2 rad is not in it.
  EXPECT_NEAR(bridge.pose().x, 0.5 + 0.5 * std::cos(0.3), 1e-9);
  EXPECT_NEAR(bridge.pose().y, 0.5 * std::sin(0.3), 1e-9);
  EXPECT_NEAR(bridge.pose().theta, 0.3, 1e-9);
  EXPECT_EQ(bridged->PathToGoal(3, 0).size(), 3u);  // 3 -> 2 -> 0 (the recognition's link)
  // After the correction 3 is where the odometry from 2 puts it.
  const auto& e = bridged->experiences();
  const Pose2D three = Between(e[2].pose(), e[3].pose());
  EXPECT_NEAR(three.x, bridge.pose().x, 0.01);
  EXPECT_NEAR(three.y, bridge.pose().y, 0.01);

  // Without it the new experience hangs off the recognised one, the recognition's placement in a
  // link as firm as odometry: 3 ends beside 0, well over a metre from where the robot drove it.
  const auto hung = RecogniseALookalikeThenCreate(false);
  EXPECT_EQ(hung->links().back().from_id, 0u);
  const auto& h = hung->experiences();
  const Pose2D hung_three = Between(h[2].pose(), h[3].pose());
  EXPECT_GT(std::hypot(hung_three.x - bridge.pose().x, hung_three.y - bridge.pose().y), 1.0);

  // Without a recognition in between, links are the same either way.
  ExperienceMapConfig config = LeastSquares(1);
  config.exp_bridge_recognitions = true;
  ExperienceMap plain(config);
  plain.Apply(Create(0, kNoExperience));
  plain.Integrate(0.7, 0.1, 1.0);
  plain.Apply(Create(1, 0));
  EXPECT_EQ(plain.links().back().from_id, 0u);
  EXPECT_NEAR(plain.links().back().d_m, 0.7, 1e-9);
}

TEST(ExperienceMap, LeastSquaresPutsTheErrorOnTheLeastSureLinks) {
  for (const double closure_sigma : {0.2, 0.02}) {  // recognition less sure than odometry, as sure
    ExperienceMapConfig cfg = LeastSquares(1);
    cfg.exp_graph_link_sigma_m = 0.02;
    cfg.exp_graph_closure_sigma_m = closure_sigma;
    ExperienceMap map(cfg);
    map.Load(SquareWithAnOffClosure(0.4));
    map.OptimiseGraph(5);
    double odometric = 0.0;
    for (int i = 0; i < 3; ++i) odometric = std::max(odometric, LinkPositionError(map, map.links()[i]));
    const double closure = LinkPositionError(map, map.links()[3]);
    if (closure_sigma > cfg.exp_graph_link_sigma_m) {
      EXPECT_LT(odometric, 0.01) << "closure " << closure;
      EXPECT_GT(closure, 0.35);
    } else {  // equally sure: the 0.4 m spread over the four links
      EXPECT_NEAR(odometric, 0.1, 0.03);
      EXPECT_NEAR(closure, 0.1, 0.03);
    }
  }
}

TEST(ExperienceMap, LeastSquaresLeavesAConsistentMapAlone) {
  ExperienceMap map(LeastSquares(1));
  map.Load(SquareWithAnOffClosure(0.0));
  map.OptimiseGraph(3);
  EXPECT_LT(map.last_correction(), 1e-12);
  EXPECT_LT(map.MaxLinkError(), 1e-12);
}

TEST(ExperienceMap, LeastSquaresStopsOnceAStepMovesNothing) {
  ExperienceMap at_once(LeastSquares(1));
  at_once.Load(SquareWithAnOffClosure(0.4));
  const PoseGraphResult result = at_once.OptimiseGraph(20, 1e-9);
  EXPECT_TRUE(result.converged);
  EXPECT_GT(result.steps, 1);
  EXPECT_LT(result.steps, 20);
  EXPECT_GT(result.largest_change, 0.02);  // the 0.4 m spread over the square (0.043 m)
  // The same as that many single steps.
  ExperienceMap stepwise(LeastSquares(1));
  stepwise.Load(SquareWithAnOffClosure(0.4));
  for (int i = 0; i < result.steps; ++i) stepwise.OptimiseGraph(1);
  for (size_t e = 0; e < at_once.experiences().size(); ++e) {
    EXPECT_NEAR(at_once.experiences()[e].x_m, stepwise.experiences()[e].x_m, 1e-12) << e;
    EXPECT_NEAR(at_once.experiences()[e].y_m, stepwise.experiences()[e].y_m, 1e-12) << e;
    EXPECT_NEAR(at_once.experiences()[e].th_rad, stepwise.experiences()[e].th_rad, 1e-12) << e;
  }
}

TEST(ExperienceMap, LeastSquaresKeepsTheFirstExperienceOfEveryUnjoinedMapInPlace) {
  ExperienceMap a(LeastSquares(1));
  a.Load(SquareWithAnOffClosure(0.4));
  ExperienceMap b(NoCorrection());
  b.Load(SquareWithAnOffClosure(0.4));
  a.MergeFrom(b, {});  // no anchor: two maps side by side, b's at its own poses
  a.OptimiseGraph(5);
  ASSERT_EQ(a.experiences().size(), 8u);
  for (uint32_t first : {0u, 4u}) {
    EXPECT_EQ(a.experiences()[first].x_m, 0.0) << first;
    EXPECT_EQ(a.experiences()[first].y_m, 0.0) << first;
    EXPECT_EQ(a.experiences()[first].th_rad, 0.0) << first;
  }
  for (const Experience& e : a.experiences()) EXPECT_TRUE(std::isfinite(e.x_m) && std::isfinite(e.th_rad));
  for (int i = 0; i < 3; ++i) {  // both squares corrected alike: the 0.4 m mostly on the closure
    EXPECT_LT(LinkPositionError(a, a.links()[i]), 0.05) << i;
    EXPECT_NEAR(LinkPositionError(a, a.links()[i]), LinkPositionError(a, a.links()[i + 4]), 1e-9) << i;
  }
}

TEST(ExperienceMap, LeastSquaresWaitsForThePeriodAfterTheLastCorrection) {
  ExperienceMap map(LeastSquares(5));
  DriveSquare(map, 1.0, 0.03);  // corrected in the closing frame: no correction for 4 frames before
  ASSERT_EQ(map.current_id(), 0u);
  map.Integrate(2.5, 0.0, 1.0);  // re-traverse 0 -> 1, half a metre longer than the first time
  map.Apply(LinkTo(Kind::kLink, 0, 1));
  for (int frame = 2; frame < 5; ++frame) {
    map.Apply(ExperienceAction{});
    EXPECT_EQ(map.last_correction(), 0.0) << frame;
  }
  map.Apply(ExperienceAction{});  // the fifth frame since the last correction
  EXPECT_GT(map.last_correction(), 0.01);
  map.Apply(ExperienceAction{});  // nothing changed since: nothing to correct
  EXPECT_EQ(map.last_correction(), 0.0);
}

// A 10 m square of 0.1 m odometric links (exact) and one recognition from the last experience to
// the first that is wrong: it says the first is `off_m` further along and turned `off_rad`.
proto::ExperienceMap LongSquareWithAWrongClosure(double off_m, double off_rad) {
  proto::ExperienceMap m;
  constexpr int kPerSide = 100;
  for (int i = 0; i < 4 * kPerSide; ++i) {
    const int side = i / kPerSide, along = i % kPerSide;
    const double th = side * kPi / 2;
    const double cx[] = {0, 10, 10, 0}, cy[] = {0, 0, 10, 10};
    auto* e = m.add_experiences();
    e->set_x_m(cx[side] + 0.1 * along * std::cos(th));
    e->set_y_m(cy[side] + 0.1 * along * std::sin(th));
    e->set_th_rad(WrapAngle(th));
  }
  const int n = 4 * kPerSide;
  for (int i = 0; i < n; ++i) {
    auto* l = m.add_links();
    l->set_from_id(i);
    l->set_to_id((i + 1) % n);
    const bool corner = (i + 1) % kPerSide == 0;
    l->set_d_m(i == n - 1 ? 0.1 + off_m : 0.1);
    l->set_facing_rad((corner ? kPi / 2 : 0.0) + (i == n - 1 ? off_rad : 0.0));
    l->set_traversals(1);
    l->set_closes_loop(i == n - 1);
  }
  m.set_has_current(true);
  m.set_current_id(n - 1);
  return m;
}

// Largest distance an experience moved from where its odometry put it.
double LargestMove(const ExperienceMap& map, const proto::ExperienceMap& before) {
  double largest = 0.0;
  for (size_t i = 0; i < map.experiences().size(); ++i)
    largest = std::max(largest, std::hypot(map.experiences()[i].x_m - before.experiences(i).x_m(),
                                           map.experiences()[i].y_m - before.experiences(i).y_m()));
  return largest;
}

TEST(ExperienceMap, LeastSquaresWithDynamicCovarianceScalingShrugsOffAWrongRecognition) {
  const proto::ExperienceMap wrong = LongSquareWithAWrongClosure(3.0, 1.0);
  ExperienceMapConfig config = LeastSquares(1);
  ExperienceMap plain(config);
  plain.Load(wrong);
  plain.OptimiseGraph(10);
  config.exp_graph_closure_robust_phi = 300;
  ExperienceMap robust(config);
  robust.Load(wrong);
  robust.OptimiseGraph(10);
  EXPECT_GT(LargestMove(plain, wrong), 5.0);   // bent by the wrong recognition (8.3 m)
  EXPECT_LT(LargestMove(robust, wrong), 1.0);  // close to its odometry (0.57 m)
  // A right recognition of a drifted loop (0.3 m, 0.02 rad off) is taken all the same.
  const proto::ExperienceMap drifted = LongSquareWithAWrongClosure(0.3, 0.02);
  ExperienceMap plain_right(LeastSquares(1)), robust_right(config);
  plain_right.Load(drifted);
  robust_right.Load(drifted);
  plain_right.OptimiseGraph(10);
  robust_right.OptimiseGraph(10);
  EXPECT_GT(LargestMove(robust_right, drifted), 0.2);
  EXPECT_NEAR(LargestMove(robust_right, drifted), LargestMove(plain_right, drifted), 0.01);
}

TEST(ExperienceMap, LeastSquaresKeysOutOfRangeAreRefused) {
  ExperienceMapConfig phi = LeastSquares(1);
  phi.exp_graph_closure_robust_phi = -1;
  EXPECT_THROW(phi.Validate(), ConfigError);
  ExperienceMapConfig period = LeastSquares(0);
  EXPECT_THROW(period.Validate(), ConfigError);
  ExperienceMapConfig sigma = LeastSquares(1);
  sigma.exp_graph_closure_sigma_rad = 0.0;
  EXPECT_THROW(sigma.Validate(), ConfigError);
  ExperienceMapConfig iterations = LeastSquares(1);
  iterations.exp_graph_iterations = 0;
  EXPECT_THROW(iterations.Validate(), ConfigError);
}

// Each (key, change) makes `base` invalid: Validate names that key.
void ExpectKeysRefused(
    const ExperienceMapConfig& base,
    std::initializer_list<std::pair<std::string, std::function<void(ExperienceMapConfig&)>>> changes) {
  for (const auto& [key, change] : changes) {
    ExperienceMapConfig c = base;
    change(c);
    try {
      c.Validate();
      ADD_FAILURE() << key << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_EQ(e.key(), key);
    }
  }
}

ExperienceMapConfig HeldToWalls() {
  ExperienceMapConfig c;
  c.exp_initial_em_deg = 0;
  c.exp_manhattan = true;
  c.exp_manhattan_reference_frames = 5;
  return c;
}

TEST(ExperienceMap, HeadingHeldToTheWallsLosesTheOdometrysDrift) {
  // The robot drives straight (true heading 0 in the map frame) past walls at 0.2 rad to it; the
  // odometry turns it 2 mrad a frame that it does not turn.
  for (bool held : {false, true}) {
    ExperienceMapConfig config = HeldToWalls();
    config.exp_manhattan = held;
    ExperienceMap map(config);
    map.Apply(Create(0, kNoExperience));
    for (int frame = 0; frame < 500; ++frame) {
      map.Integrate(0.25, 0.02, 0.1);
      map.HoldHeading(-0.2);  // the walls in the robot frame: at 0.2 rad in the truth's
      map.Apply(frame % 10 == 9 ? Create(frame / 10 + 1, frame / 10) : ExperienceAction{});
    }
    if (!held) {
      EXPECT_NEAR(map.RobotPose().theta, 1.0, 1e-9);
      EXPECT_FALSE(map.manhattan_axes().has_value());
      continue;
    }
    // The axes were fixed after 5 frames (6 mrad of drift on average); the heading then holds
    // where a frame's drift (2 mrad) is the gain's share (0.2) of the offset: 6 + 10 - 2 mrad.
    ASSERT_TRUE(map.manhattan_axes().has_value());
    EXPECT_NEAR(*map.manhattan_axes(), -0.2 + 0.006, 1e-9);
    EXPECT_NEAR(map.RobotPose().theta, 0.014, 1e-6);
    // So are the experiences it laid and the links between them.
    EXPECT_NEAR(map.experiences().back().th_rad, 0.014, 1e-6);
    EXPECT_NEAR(map.links().back().facing_rad, 0.0, 1e-3);
  }
}

TEST(ExperienceMap, HeadingHoldIgnoresOtherWallsAndRefusesBadDirections) {
  ExperienceMap map(HeldToWalls());
  for (int i = 0; i < 5; ++i) map.HoldHeading(0.0);  // fixes the axes at 0
  ASSERT_TRUE(map.manhattan_axes().has_value());
  EXPECT_NEAR(*map.manhattan_axes(), 0.0, 1e-12);
  map.HoldHeading(0.1);  // a wall 0.1 rad off: the heading turns a fifth of it back
  EXPECT_NEAR(map.RobotPose().theta, -0.02, 1e-12);
  map.HoldHeading(0.6);  // 0.6 rad off: some other wall
  EXPECT_NEAR(map.RobotPose().theta, -0.02, 1e-12);
  EXPECT_THROW(map.HoldHeading(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_NEAR(map.RobotPose().theta, -0.02, 1e-12);

  // Reference directions that disagree (a corner of odd angle, a table) fix nothing.
  ExperienceMap scattered(HeldToWalls());
  for (double d : {0.0, 0.3, -0.3, 0.15, 0.4}) scattered.HoldHeading(d);
  EXPECT_FALSE(scattered.manhattan_axes().has_value());

  // The first directions in a row that agree fix the axes wherever they start: here five after
  // two odd ones (blocks of five counted from the first, as until session 67, would wait for the
  // second block).
  ExperienceMap straddled(HeldToWalls());
  for (double d : {0.44, -0.34, 0.05, 0.05, 0.05, 0.05, 0.05}) {
    EXPECT_FALSE(straddled.manhattan_axes().has_value());
    straddled.HoldHeading(d);
  }
  ASSERT_TRUE(straddled.manhattan_axes().has_value());
  EXPECT_NEAR(*straddled.manhattan_axes(), 0.05, 1e-12);

  // The axes and the half-gathered reference survive a save and a load.
  ExperienceMap half(HeldToWalls());
  for (int i = 0; i < 3; ++i) half.HoldHeading(0.1);
  ExperienceMap loaded(HeldToWalls());
  loaded.Load(half.Save());
  for (int i = 0; i < 2; ++i) loaded.HoldHeading(0.1);
  ASSERT_TRUE(loaded.manhattan_axes().has_value());
  EXPECT_NEAR(*loaded.manhattan_axes(), 0.1, 1e-12);
  ExperienceMap reloaded(HeldToWalls());
  reloaded.Load(loaded.Save());
  EXPECT_EQ(reloaded.manhattan_axes(), loaded.manhattan_axes());
  // A reference gathered with a longer window keeps its latest directions under a shorter one.
  ExperienceMap gathered(HeldToWalls());
  for (double d : {0.4, 0.1, 0.1, 0.1}) gathered.HoldHeading(d);
  ExperienceMapConfig shorter = HeldToWalls();
  shorter.exp_manhattan_reference_frames = 3;
  ExperienceMap trimmed(shorter);
  trimmed.Load(gathered.Save());
  EXPECT_FALSE(trimmed.manhattan_axes().has_value());
  trimmed.HoldHeading(0.1);  // 0.1, 0.1, 0.1: the 0.4 was dropped
  ASSERT_TRUE(trimmed.manhattan_axes().has_value());
  EXPECT_NEAR(*trimmed.manhattan_axes(), 0.1, 1e-12);

  ExpectKeysRefused(HeldToWalls(),
                    {{"exp_manhattan_gain", [](ExperienceMapConfig& c) { c.exp_manhattan_gain = 0; }},
                     {"exp_manhattan_max_offset_rad", [](ExperienceMapConfig& c) { c.exp_manhattan_max_offset_rad = 0.8; }},
                     {"exp_manhattan_reference_frames", [](ExperienceMapConfig& c) { c.exp_manhattan_reference_frames = 0; }}});
}

// The last Apply refused a recognition at `gate`, which it would have passed by `value` against
// `limit`; its log line names `key` and both figures.
void ExpectRefusal(const ExperienceMap& map, RecognitionRefusal::Gate gate, double value, double limit,
                   const std::string& key) {
  ASSERT_TRUE(map.last_refusal().has_value());
  const RecognitionRefusal& r = *map.last_refusal();
  EXPECT_EQ(r.gate, gate);
  EXPECT_NEAR(r.value, value, 1e-9);
  EXPECT_NEAR(r.limit, limit, 1e-9);
  const std::string line = ToString(r);
  char figures[32];
  std::snprintf(figures, sizeof(figures), "%.2f", value);
  EXPECT_NE(line.find(figures), std::string::npos) << line;
  std::snprintf(figures, sizeof(figures), "%.2f", limit);
  EXPECT_NE(line.find(figures), std::string::npos) << line;
  EXPECT_NE(line.find(key), std::string::npos) << line;
}

TEST(ExperienceMap, ARecognitionFarFromWhereTheMapHasTheRobotIsRefused) {
  ExperienceMapConfig config = NoCorrection();  // the experiences stay where they were laid
  config.exp_initial_em_deg = 0;
  config.exp_recognition_max_jump_m = 2.0;
  config.exp_recognition_jump_per_m = 0.5;
  ExperienceMap map(config);
  map.Apply(Create(0, kNoExperience));
  map.Integrate(5.0, 0.0, 1.0);
  map.Apply(Create(1, 0));
  map.Integrate(5.0, 0.0, 1.0);
  map.Apply(Create(2, 1));
  map.Integrate(1.0, 0.0, 1.0);  // the robot at (11, 0), 11 m driven since the start: 7.5 m allowed
  ASSERT_EQ(map.links().size(), 2u);

  // Experience 0, 11 m behind: refused. No link; the robot stays; the pose cells' current
  // experience (0) is accepted as the origin of their next action, which the map takes from its own.
  map.Apply(LinkTo(Kind::kLink, 2, 0));
  EXPECT_EQ(map.refused_recognitions(), 1u);
  ExpectRefusal(map, RecognitionRefusal::Gate::kJump, 11.0, 7.5, "exp_recognition_max_jump_m");
  EXPECT_EQ(map.links().size(), 2u);
  EXPECT_EQ(map.current_id(), 2u);
  EXPECT_EQ(map.pose_cells_current(), std::optional<uint32_t>(0));
  EXPECT_NEAR(map.RobotPose().x, 11.0, 1e-9);

  // A saved and loaded map keeps that.
  ExperienceMap loaded(config);
  loaded.Load(map.Save());
  EXPECT_EQ(loaded.pose_cells_current(), std::optional<uint32_t>(0));
  map.Apply(Create(3, 0));
  loaded.Apply(Create(3, 0));
  for (const ExperienceMap* m : {&map, &loaded}) {
    EXPECT_EQ(m->links().back().from_id, 2u);
    EXPECT_NEAR(m->links().back().d_m, 1.0, 1e-9);
    EXPECT_NEAR(m->experiences()[3].x_m, 11.0, 1e-9);
    EXPECT_FALSE(m->pose_cells_current().has_value());
  }
  EXPECT_THROW(map.Apply(LinkTo(Kind::kLink, 0, 1)), std::invalid_argument);  // 0 is nobody's current now

  // Experience 1, 6 m behind: taken (the robot put on it), and the distance allowed starts
  // again from 2 m.
  map.Apply(LinkTo(Kind::kLink, 3, 1));
  EXPECT_EQ(map.refused_recognitions(), 1u);
  EXPECT_FALSE(map.last_refusal().has_value());
  EXPECT_TRUE(map.links().back().closes_loop);
  EXPECT_EQ(map.current_id(), 1u);
  EXPECT_NEAR(map.RobotPose().x, 5.0, 1e-9);
  map.Integrate(1.0, 0.0, 1.0);
  map.Integrate(-1.0, 0.0, 1.0);  // 2 m driven, back at (5, 0): 3 m allowed
  map.Apply(LinkTo(Kind::kSet, 1, 2));  // 5 m
  EXPECT_EQ(map.refused_recognitions(), 2u);
  EXPECT_EQ(map.current_id(), 1u);
  map.Integrate(2.5, 0.0, 1.0);
  map.Integrate(-2.5, 0.0, 1.0);  // 7 m driven: 5.5 m allowed
  map.Apply(LinkTo(Kind::kSet, 2, 3));  // 6 m, from the pose cells' current
  EXPECT_EQ(map.refused_recognitions(), 3u);
  EXPECT_EQ(map.pose_cells_current(), std::optional<uint32_t>(3));
  map.Apply(LinkTo(Kind::kSet, 3, 0));  // 5 m: taken
  EXPECT_EQ(map.refused_recognitions(), 3u);
  EXPECT_EQ(map.current_id(), 0u);
  EXPECT_FALSE(map.pose_cells_current().has_value());

  ExpectKeysRefused(config,
                    {{"exp_recognition_max_jump_m", [](ExperienceMapConfig& c) { c.exp_recognition_max_jump_m = -1; }},
                     {"exp_recognition_jump_per_m", [](ExperienceMapConfig& c) { c.exp_recognition_jump_per_m = NAN; }}});
}

// The jump gate's allowance grows with the distance driven only up to exp_recognition_jump_cap_m:
// 11 m driven would allow 7.5 m, the cap 4 m, so a place 6 m behind is refused with the cap and
// taken without it.
TEST(ExperienceMap, TheJumpGatesAllowanceStopsGrowingAtItsCap) {
  ExperienceMapConfig uncapped = NoCorrection();
  uncapped.exp_initial_em_deg = 0;
  uncapped.exp_recognition_max_jump_m = 2.0;
  uncapped.exp_recognition_jump_per_m = 0.5;
  ExperienceMapConfig capped = uncapped;
  capped.exp_recognition_jump_cap_m = 4.0;
  for (const ExperienceMapConfig* config : {&uncapped, &capped}) {
    ExperienceMap map(*config);
    map.Apply(Create(0, kNoExperience));
    map.Integrate(5.0, 0.0, 1.0);
    map.Apply(Create(1, 0));
    map.Integrate(5.0, 0.0, 1.0);
    map.Apply(Create(2, 1));
    map.Integrate(1.0, 0.0, 1.0);  // the robot at (11, 0), 11 m driven since the start
    map.Apply(LinkTo(Kind::kLink, 2, 1));  // experience 1, 6 m behind
    if (config == &capped) {
      ExpectRefusal(map, RecognitionRefusal::Gate::kJump, 6.0, 4.0, "_jump_cap_m");
      EXPECT_EQ(map.current_id(), 2u);
    } else {
      EXPECT_FALSE(map.last_refusal().has_value());
      EXPECT_EQ(map.current_id(), 1u);
    }
  }
  ExpectKeysRefused(capped,
                    {{"exp_recognition_jump_cap_m", [](ExperienceMapConfig& c) { c.exp_recognition_jump_cap_m = 1.0; }},
                     {"exp_recognition_jump_cap_m", [](ExperienceMapConfig& c) { c.exp_recognition_jump_cap_m = NAN; }},
                     {"exp_recognition_jump_cap_m", [](ExperienceMapConfig& c) { c.exp_recognition_jump_cap_m = -1; }}});
}

// A recognition of the stretch the robot is on (a step back along it) says nothing of how far the
// map has drifted, so with exp_recognition_jump_local_ids it does not restart the distance the
// jump gate allows for; one of a place farther back in the map still does.
TEST(ExperienceMap, ARecognitionOfTheStretchTheRobotIsOnDoesNotRestartTheJumpGate) {
  ExperienceMapConfig config = NoCorrection();  // the experiences stay where they were laid
  config.exp_initial_em_deg = 0;
  config.exp_recognition_max_jump_m = 1.0;
  config.exp_recognition_jump_per_m = 0.6;
  ExperienceMapConfig local = config;
  local.exp_recognition_jump_local_ids = 2;
  ExperienceMap every(config), stretch(local);
  for (ExperienceMap* map : {&every, &stretch}) {
    map->Apply(Create(0, kNoExperience));
    for (uint32_t id = 1; id <= 4; ++id) {
      map->Integrate(1.0, 0.0, 1.0);
      map->Apply(Create(id, id - 1));
    }
    // At (4, 0), 4 m driven: 3.4 m allowed. Experience 3, a step back: taken by both.
    map->Apply(LinkTo(Kind::kSet, 4, 3));
    EXPECT_EQ(map->refused_recognitions(), 0u);
    EXPECT_EQ(map->current_id(), 3u);
    // Experience 0, 3 m behind.
    map->Apply(LinkTo(Kind::kSet, 3, 0));
  }
  // Restarted at experience 3 (1 m allowed): refused.
  EXPECT_EQ(every.refused_recognitions(), 1u);
  ExpectRefusal(every, RecognitionRefusal::Gate::kJump, 3.0, 1.0, "exp_recognition_max_jump_m");
  EXPECT_EQ(every.current_id(), 3u);
  // Not restarted there (3.4 m allowed): taken, and that restarts it.
  EXPECT_EQ(stretch.refused_recognitions(), 0u);
  EXPECT_EQ(stretch.current_id(), 0u);
  stretch.Apply(LinkTo(Kind::kSet, 0, 4));  // 4 m ahead, 1 m allowed
  EXPECT_EQ(stretch.refused_recognitions(), 1u);
  ExpectRefusal(stretch, RecognitionRefusal::Gate::kJump, 4.0, 1.0, "exp_recognition_max_jump_m");

  // The distance so far survives a save and a load.
  ExperienceMap loaded(local);
  loaded.Load(stretch.Save());
  loaded.Apply(LinkTo(Kind::kSet, 0, 4));
  ExpectRefusal(loaded, RecognitionRefusal::Gate::kJump, 4.0, 1.0, "exp_recognition_max_jump_m");

  ExpectKeysRefused(local, {{"exp_recognition_jump_local_ids",
                             [](ExperienceMapConfig& c) { c.exp_recognition_jump_local_ids = -1; }}});
}

// The experiences stay where they were laid; a recognition that would turn the robot more than
// 0.5 rad is refused.
ExperienceMapConfig TurnGated() {
  ExperienceMapConfig config = NoCorrection();
  config.exp_initial_em_deg = 0;
  config.exp_recognition_max_turn_rad = 0.5;
  return config;
}

// Three experiences on three sides of a unit square, the robot left at (0, 1) facing -x.
void DriveThreeSides(ExperienceMap& map) {
  map.Apply(Create(0, kNoExperience));  // at (0, 0) facing +x
  map.Integrate(1.0, 0.0, 1.0);
  map.Apply(Create(1, 0));  // at (1, 0) facing +x
  map.Integrate(0.0, kPi / 2, 1.0);
  map.Integrate(1.0, 0.0, 1.0);
  map.Apply(Create(2, 1));  // at (1, 1) facing +y
  map.Integrate(0.0, kPi / 2, 1.0);
  map.Integrate(1.0, 0.0, 1.0);  // at (0, 1) facing -x
}

TEST(ExperienceMap, ARecognitionThatWouldTurnTheRobotFarIsRefused) {
  ExperienceMapConfig config = TurnGated();
  ExperienceMap map(config);
  DriveThreeSides(map);

  // Experience 0 seen facing as it was made (+x): a half turn from the robot's facing. Refused,
  // the robot's pose unchanged.
  map.Apply(LinkTo(Kind::kLink, 2, 0));
  EXPECT_EQ(map.refused_recognitions(), 1u);
  ExpectRefusal(map, RecognitionRefusal::Gate::kTurn, kPi, 0.5, "exp_recognition_max_turn_rad");
  EXPECT_EQ(map.current_id(), 2u);
  EXPECT_EQ(map.pose_cells_current(), std::optional<uint32_t>(0));
  EXPECT_NEAR(map.RobotPose().theta, kPi, 1e-9);

  // Seen at a relative angle that puts the robot within 0.5 rad of its facing: taken.
  ExperienceAction facing = LinkTo(Kind::kLink, 0, 1);
  facing.relative_angle_rad = kPi - 0.4;
  map.Apply(facing);
  EXPECT_EQ(map.refused_recognitions(), 1u);
  EXPECT_EQ(map.current_id(), 1u);
  EXPECT_NEAR(map.RobotPose().theta, kPi - 0.4, 1e-9);

  // A set (a transition along a link) is turned only with exp_set_view_angle.
  map.Integrate(0.0, kPi, 1.0);  // facing -0.4 rad; experience 2 faces +y
  config.exp_set_view_angle = false;
  ExperienceMap unturned(config);
  unturned.Load(map.Save());
  map.Apply(LinkTo(Kind::kSet, 1, 2));
  EXPECT_EQ(map.refused_recognitions(), 2u);
  unturned.Apply(LinkTo(Kind::kSet, 1, 2));
  EXPECT_EQ(unturned.refused_recognitions(), 1u);
  EXPECT_EQ(unturned.current_id(), 2u);
  EXPECT_NEAR(unturned.RobotPose().theta, -0.4, 1e-9);

  ExpectKeysRefused(config, {{"exp_recognition_max_turn_rad", [](ExperienceMapConfig& c) { c.exp_recognition_max_turn_rad = 4; }}});
}

// After a refused recognition the pose cells go on from the refused place: their next set is to
// a neighbour of it, which the map has not linked to its current experience. The turn gate holds
// for it with the view's angle, as for the link before it.
TEST(ExperienceMap, ASetAfterARefusedRecognitionFacesTheTurnGate) {
  ExperienceMapConfig config = TurnGated();
  config.exp_set_view_angle = false;  // a set keeps the map's facing, as in the demo
  ExperienceMap map(config);
  DriveThreeSides(map);
  map.Apply(LinkTo(Kind::kLink, 2, 0));  // a half turn: refused
  ASSERT_EQ(map.pose_cells_current(), std::optional<uint32_t>(0));

  // The pose cells step from 0 to 1, seen as made (facing +x): refused too, the robot where it was.
  map.Apply(LinkTo(Kind::kSet, 0, 1));
  EXPECT_EQ(map.refused_recognitions(), 2u);
  ExpectRefusal(map, RecognitionRefusal::Gate::kTurn, kPi, 0.5, "exp_recognition_max_turn_rad");
  EXPECT_EQ(map.current_id(), 2u);
  EXPECT_EQ(map.pose_cells_current(), std::optional<uint32_t>(1));
  EXPECT_NEAR(map.RobotPose().x, 0.0, 1e-9);
  EXPECT_NEAR(map.RobotPose().y, 1.0, 1e-9);

  // A step back to 0 seen at a relative angle within 0.5 rad of the robot's facing: taken.
  ExperienceAction facing = LinkTo(Kind::kSet, 1, 0);
  facing.relative_angle_rad = kPi - 0.4;
  map.Apply(facing);
  EXPECT_EQ(map.refused_recognitions(), 2u);
  EXPECT_EQ(map.current_id(), 0u);
  EXPECT_FALSE(map.pose_cells_current().has_value());

  // With the map's and the pose cells' current experience the same, a set is not turn-gated
  // (exp_set_view_angle off): a step to 1, whatever the view's angle.
  map.Apply(LinkTo(Kind::kSet, 0, 1));
  EXPECT_EQ(map.refused_recognitions(), 2u);
  EXPECT_EQ(map.current_id(), 1u);
}

TEST(ExperienceMap, ARecognitionWhoseLinkWouldJoinPlacesFarApartIsRefused) {
  ExperienceMapConfig config = NoCorrection();  // the experiences stay where they were laid
  config.exp_initial_em_deg = 0;
  config.exp_recognition_max_link_m = 1.5;
  const auto drive = [](ExperienceMap& m) {
    m.Apply(Create(0, kNoExperience));
    m.Integrate(1.0, 0.0, 1.0);
    m.Apply(Create(1, 0));  // at (1, 0)
    m.Integrate(1.0, 0.0, 1.0);
    m.Apply(Create(2, 1));  // at (2, 0)
    m.Integrate(-1.0, 0.0, 1.0);  // back at (1, 0)
  };
  ExperienceMap map(config);
  drive(map);

  // Experience 0 seen 1 m ahead of the robot, just where the map has it: the link from
  // experience 2 to it would be 2 m long. Refused: no link, the robot stays.
  ExperienceAction far = LinkTo(Kind::kLink, 2, 0);
  far.offset_x_m = 1.0;
  map.Apply(far);
  EXPECT_EQ(map.refused_recognitions(), 1u);
  ExpectRefusal(map, RecognitionRefusal::Gate::kLink, 2.0, 1.5, "exp_recognition_max_link_m");
  EXPECT_EQ(map.links().size(), 2u);
  EXPECT_EQ(map.current_id(), 2u);
  EXPECT_NEAR(map.RobotPose().x, 1.0, 1e-9);

  // Experience 1, where the robot stands: 1 m from experience 2, taken (averaged into the link
  // that made experience 2).
  map.Apply(LinkTo(Kind::kLink, 0, 1));
  EXPECT_EQ(map.refused_recognitions(), 1u);
  EXPECT_EQ(map.links().size(), 2u);
  EXPECT_EQ(map.current_id(), 1u);

  // A set makes no link, so its length is not judged: experience 0 is taken.
  map.Apply(LinkTo(Kind::kSet, 1, 0));
  EXPECT_EQ(map.refused_recognitions(), 1u);
  EXPECT_EQ(map.current_id(), 0u);

  // Without the key the 2-m link is made.
  config.exp_recognition_max_link_m = 0;
  ExperienceMap any(config);
  drive(any);
  any.Apply(far);
  EXPECT_EQ(any.refused_recognitions(), 0u);
  EXPECT_TRUE(any.links().back().closes_loop);
  EXPECT_NEAR(any.links().back().d_m, 2.0, 1e-9);

  ExpectKeysRefused(config, {{"exp_recognition_max_link_m", [](ExperienceMapConfig& c) { c.exp_recognition_max_link_m = -0.1; }}});
}

TEST(ExperienceMap, HeadingThatDriftedPastTheGateIsTakenBackWhenTheWallsAgreeOnIt) {
  // Heading 0.4 rad off the axes, past the gate's 0.3: walls on the axes all come 0.4 off.
  ExperienceMapConfig config = HeldToWalls();
  config.exp_manhattan_min_offset_rad = 0.1;
  config.exp_manhattan_offset_per_rad_turned = 0.1;
  config.exp_manhattan_max_offset_rad = 0.3;
  const auto drifted = [&](int recapture_frames) {
    ExperienceMapConfig c = config;
    c.exp_manhattan_recapture_frames = recapture_frames;
    auto map = std::make_unique<ExperienceMap>(c);
    for (int i = 0; i < 5; ++i) map->HoldHeading(0.0);  // fixes the axes at 0
    map->Integrate(0.0, 0.4, 1.0);  // a turn the robot did not make
    return map;
  };
  // The robot turns 0.12 rad a frame and sees a wall on an axis each time: the wall direction
  // (robot frame) that puts it `offset` off the axes.
  const auto turn_and_see = [](ExperienceMap& map, double offset) {
    map.Integrate(0.0, 0.12, 1.0);
    map.HoldHeading(offset - map.RobotPose().theta);
  };
  const double noise[] = {0.02, -0.01, 0.0, 0.015, -0.02, 0.01, -0.015, 0.005, 0.0, -0.005};
  // Off: never pulled back.
  auto off = drifted(0);
  for (double n : noise) turn_and_see(*off, 0.4 + n);
  EXPECT_NEAR(off->RobotPose().theta, 1.6, 1e-9);
  EXPECT_EQ(off->heading_recaptures(), 0u);
  // Ten agreeing offsets over more than a radian of turning: the drift (their mean, 0.4) taken
  // out at once.
  auto on = drifted(10);
  for (double n : noise) turn_and_see(*on, 0.4 + n);
  EXPECT_NEAR(on->RobotPose().theta, 1.6 - 0.4, 1e-4);
  EXPECT_EQ(on->heading_recaptures(), 1u);
  const double recaptured = on->RobotPose().theta;
  turn_and_see(*on, 0.05);  // within the gate again: held as before
  EXPECT_NEAR(on->RobotPose().theta, recaptured + 0.12 - 0.01, 1e-9);
  // A wall the widest gate would hold (0.29 rad off: a funnel's side seen while the gate is
  // narrow) breaks the row: ten more are needed after it.
  auto broken = drifted(10);
  for (int i = 0; i < 10; ++i) turn_and_see(*broken, i == 5 ? 0.29 : 0.4);
  EXPECT_EQ(broken->heading_recaptures(), 0u);
  for (int i = 0; i < 6; ++i) turn_and_see(*broken, 0.4);
  EXPECT_EQ(broken->heading_recaptures(), 1u);
  // Walls off the axes (a funnel's two sides, 0.35 rad either way) disagree: nothing taken.
  auto funnel = drifted(10);
  for (int i = 0; i < 30; ++i) turn_and_see(*funnel, i % 2 ? 0.35 : -0.35);
  EXPECT_EQ(funnel->heading_recaptures(), 0u);
  EXPECT_NEAR(funnel->RobotPose().theta, WrapAngle(0.4 + 3.6), 1e-9);
  // Walls 0.6 rad off, past exp_manhattan_recapture_max_rad (0.5): as near 45 degrees to the
  // axes as to them, nothing taken.
  auto diagonal = drifted(10);
  for (double n : noise) turn_and_see(*diagonal, 0.6 + n);
  EXPECT_EQ(diagonal->heading_recaptures(), 0u);
  // The walls seen while the robot hardly turns (one wall, maybe off the axes): nothing taken.
  auto still = drifted(10);
  for (double n : noise) {
    still->Integrate(0.0, 0.01, 1.0);
    still->HoldHeading(0.4 + n - still->RobotPose().theta);
  }
  EXPECT_EQ(still->heading_recaptures(), 0u);

  ExpectKeysRefused(config, {{"exp_manhattan_recapture_frames",
                              [](ExperienceMapConfig& c) { c.exp_manhattan_recapture_frames = -1; }},
                             {"exp_manhattan_recapture_spread_rad",
                              [](ExperienceMapConfig& c) { c.exp_manhattan_recapture_spread_rad = 0; }},
                             {"exp_manhattan_recapture_turn_rad",
                              [](ExperienceMapConfig& c) { c.exp_manhattan_recapture_turn_rad = NAN; }},
                             {"exp_manhattan_recapture_max_rad",
                              [](ExperienceMapConfig& c) { c.exp_manhattan_recapture_max_rad = 0.8; }}});
}

// The demo's heading hold: gates 0.1 rad after a hold, widening 0.1 a radian turned, up to 0.25,
// tapered; twenty offsets past the gate of the moment over half a radian recapture the heading.
ExperienceMapConfig DemoHeadingHold() {
  ExperienceMapConfig c = HeldToWalls();
  c.exp_manhattan_min_offset_rad = 0.1;
  c.exp_manhattan_offset_per_rad_turned = 0.1;
  c.exp_manhattan_max_offset_rad = 0.25;
  c.exp_manhattan_taper = true;
  c.exp_manhattan_recapture_frames = 20;
  c.exp_manhattan_recapture_turn_rad = 0.5;
  c.exp_manhattan_recapture_inside_widest = true;
  return c;
}

// The robot's heading error in the map after a scene, and the recaptures it took.
struct HeadingResult {
  double error_rad;
  uint64_t recaptures;
};

TEST(ExperienceMap, AHeadingBetweenTheGatesIsTakenBackWhenTheWallsAfterItAgree) {
  // The demo's heading hold. A quarter turn read 0.18 rad too far (AC26, session 69: 0.17 rad at
  // frame 6,100); then the robot drives on, turning `turn_per_frame`, and sees walls on the axes:
  // each comes 0.18 off.
  const ExperienceMapConfig config = DemoHeadingHold();
  const double noise[] = {0.01, -0.005, 0.0, 0.008, -0.01};
  const auto after_misread_turn = [&](bool inside_widest, double turn_per_frame) {
    ExperienceMapConfig c = config;
    c.exp_manhattan_recapture_inside_widest = inside_widest;
    ExperienceMap map(c);
    for (int i = 0; i < 5; ++i) map.HoldHeading(0.0);  // fixes the axes at 0, the robot on one
    for (int i = 0; i < 10; ++i) map.Integrate(0.0, kPi / 2 + 0.18, 0.1);  // truly a quarter turn, in 1 s
    double turned = 0.0;  // truly, since
    for (int frame = 0; frame < 60; ++frame) {
      map.Integrate(0.25, turn_per_frame / 0.1, 0.1);
      turned += turn_per_frame;
      map.HoldHeading(noise[frame % 5] - turned);  // a wall on an axis, in the robot's frame
    }
    return HeadingResult{WrapAngle(map.RobotPose().theta - kPi / 2 - turned), map.heading_recaptures()};
  };
  // The first wall after the turn is held, tapered to 0.17 of the pull (0.007 rad back), and the
  // gate narrows to 0.1 again. Without the key, each wall the gate lets in as it widens with the
  // turning is held as weakly and narrows it again: after 60 frames (1.8 rad) still 0.14 rad off.
  const HeadingResult without = after_misread_turn(false, 0.03);
  EXPECT_GT(without.error_rad, 0.12);
  EXPECT_EQ(without.recaptures, 0u);
  // With it, twenty offsets in a row past the gate that agree, over half a radian of turning, are
  // the heading's drift: taken out at once.
  const HeadingResult with = after_misread_turn(true, 0.03);
  EXPECT_LT(std::abs(with.error_rad), 0.01);
  EXPECT_EQ(with.recaptures, 1u);
  // Driving on hardly turning (one wall, maybe off the axes): nothing taken, with it as without.
  EXPECT_EQ(after_misread_turn(true, 0.001).recaptures, 0u);
}

TEST(ExperienceMap, OneWallOffTheAxesSeenOverAWideTurnIsNotTakenForDrift) {
  // The demo's heading hold. The heading is right; the robot turns on the spot, `turn_per_frame`,
  // and sees walls in the map's directions `seen(frame)` (0 and pi/2: the two axes).
  const ExperienceMapConfig config = DemoHeadingHold();
  const double noise[] = {0.01, -0.005, 0.0, 0.008, -0.01};
  const auto spin = [&](double one_axis_turn_rad, double turn_per_frame, auto seen, double drift_rad) {
    ExperienceMapConfig c = config;
    c.exp_manhattan_recapture_one_axis_turn_rad = one_axis_turn_rad;
    ExperienceMap map(c);
    for (int i = 0; i < 5; ++i) map.HoldHeading(0.0);  // fixes the axes at 0
    map.Integrate(0.0, drift_rad, 1.0);                 // a turn the robot did not make
    double truly = 0.0;
    for (int frame = 0; frame < 30; ++frame) {
      map.Integrate(0.0, turn_per_frame, 1.0);
      truly += turn_per_frame;
      map.HoldHeading(seen(frame) + noise[frame % 5] - truly);  // in the robot's frame
    }
    return HeadingResult{WrapAngle(map.RobotPose().theta - truly), map.heading_recaptures()};
  };
  // One wall 0.3 rad off the axes, seen again and again over 4.5 rad of turning (AG3, session 73:
  // 0.26 rad taken out of a right heading over 6.4 rad). Without the key it is taken for drift;
  // with the demo's (the camera's field of view, 60 degrees) it is not.
  const auto one_wall = [](int) { return 0.3; };
  const HeadingResult taken = spin(0.0, 0.15, one_wall, 0.0);
  EXPECT_EQ(taken.recaptures, 1u);
  EXPECT_NEAR(taken.error_rad, -0.3, 0.02);
  const HeadingResult kept = spin(kPi / 3, 0.15, one_wall, 0.0);
  EXPECT_EQ(kept.recaptures, 0u);
  EXPECT_NEAR(kept.error_rad, 0.0, 1e-9);
  // A heading 0.3 rad off: over the same turn walls of both axes come 0.3 off. Taken back.
  const auto both_axes = [](int frame) { return frame % 3 ? 0.0 : kPi / 2; };
  const HeadingResult both = spin(kPi / 3, 0.15, both_axes, 0.3);
  EXPECT_EQ(both.recaptures, 1u);
  EXPECT_LT(std::abs(both.error_rad), 0.02);
  // ... and over a narrower turn (0.8 rad over the twenty) one axis's walls are enough, as before.
  const HeadingResult narrow = spin(kPi / 3, 0.04, [](int) { return 0.0; }, 0.3);
  EXPECT_EQ(narrow.recaptures, 1u);
  EXPECT_LT(std::abs(narrow.error_rad), 0.02);

  ExpectKeysRefused(config, {{"exp_manhattan_recapture_one_axis_turn_rad",
                              [](ExperienceMapConfig& c) { c.exp_manhattan_recapture_one_axis_turn_rad = -1; }}});
}

TEST(ExperienceMap, ARobotStandingBeforeOneWallGivesOneLookTowardARecapture) {
  // The demo's heading hold. The heading is right; the robot stands 14 frames before one wall
  // 0.49 rad off the axes, then turns 0.57 rad on the spot in 7 frames, the wall in view all the
  // while (AQ24, session 80, frames 711-731: 0.494 rad taken out of a right heading, and the map
  // drawn 0.5-0.8 rad off for the 12,000 frames until it was taken back).
  const double noise[] = {0.004, -0.002, 0.0, 0.003, -0.004};
  const auto stand_then_turn = [&](bool moving_frames) {
    ExperienceMapConfig c = DemoHeadingHold();
    c.exp_manhattan_recapture_one_axis_turn_rad = kPi / 3;
    c.exp_manhattan_recapture_moving_frames = moving_frames;
    ExperienceMap map(c);
    for (int i = 0; i < 5; ++i) map.HoldHeading(0.0);  // fixes the axes at 0
    double truly = 0.0;
    for (int frame = 0; frame < 30; ++frame) {
      const double turn = frame >= 14 && frame < 21 ? 0.57 / 7 : 0.0;  // then stands again
      map.Integrate(0.0, turn, 1.0);
      truly += turn;
      map.HoldHeading(0.49 + noise[frame % 5] - truly);  // in the robot's frame
    }
    return HeadingResult{WrapAngle(map.RobotPose().theta - truly), map.heading_recaptures()};
  };
  // Counting each frame, the standing frames make up the twenty: taken for drift.
  const HeadingResult counted = stand_then_turn(false);
  EXPECT_EQ(counted.recaptures, 1u);
  EXPECT_NEAR(counted.error_rad, -0.49, 0.01);
  // Counting the frames that moved, 7 looks: the heading is left as it was.
  const HeadingResult looks = stand_then_turn(true);
  EXPECT_EQ(looks.recaptures, 0u);
  EXPECT_NEAR(looks.error_rad, 0.0, 1e-9);
  // Looks enough while turning still take a drift back: a heading 0.45 rad off, walls on an axis.
  ExperienceMapConfig c = DemoHeadingHold();
  c.exp_manhattan_recapture_moving_frames = true;
  ExperienceMap turning(c);
  for (int i = 0; i < 5; ++i) turning.HoldHeading(0.0);
  turning.Integrate(0.0, 0.45, 1.0);
  double truly = 0.0;
  for (int frame = 0; frame < 25; ++frame) {
    turning.Integrate(0.0, 0.04, 1.0);
    truly += 0.04;
    turning.HoldHeading(noise[frame % 5] - truly);
  }
  EXPECT_EQ(turning.heading_recaptures(), 1u);
  EXPECT_LT(std::abs(WrapAngle(turning.RobotPose().theta - truly)), 0.01);
}

TEST(ExperienceMap, HeadingHoldGateIsNarrowAfterAHeldWallAndWidensAsTheRobotTurns) {
  ExperienceMapConfig config = HeldToWalls();
  config.exp_manhattan_min_offset_rad = 0.1;
  config.exp_manhattan_offset_per_rad_turned = 0.1;
  config.exp_manhattan_max_offset_rad = 0.3;
  ExperienceMap map(config);
  for (int i = 0; i < 5; ++i) map.HoldHeading(0.0);  // fixes the axes at 0
  ASSERT_TRUE(map.manhattan_axes().has_value());
  // A wall direction that leaves the heading `offset` off the axes.
  auto wall_at = [&](double offset) { return offset - map.RobotPose().theta; };
  map.HoldHeading(wall_at(0.05));  // within 0.1: held, a fifth of it taken out
  EXPECT_NEAR(map.RobotPose().theta, -0.01, 1e-12);
  map.HoldHeading(wall_at(0.15));  // just held: the gate is 0.1
  EXPECT_NEAR(map.RobotPose().theta, -0.01, 1e-12);

  map.Integrate(0.0, 1.0, 1.0);  // a radian turned: the gate is 0.2
  EXPECT_NEAR(map.RobotPose().theta, 0.99, 1e-12);
  map.HoldHeading(wall_at(0.25));
  EXPECT_NEAR(map.RobotPose().theta, 0.99, 1e-12);
  map.HoldHeading(wall_at(0.15));
  EXPECT_NEAR(map.RobotPose().theta, 0.99 - 0.03, 1e-12);
  map.HoldHeading(wall_at(0.15));  // narrow again
  EXPECT_NEAR(map.RobotPose().theta, 0.96, 1e-12);

  map.Integrate(0.0, -1.0, 5.0);  // five radians either way: at most 0.3
  map.HoldHeading(wall_at(0.35));
  EXPECT_NEAR(map.RobotPose().theta, WrapAngle(0.96 - 5.0), 1e-12);
  map.HoldHeading(wall_at(0.28));
  EXPECT_NEAR(map.RobotPose().theta, WrapAngle(0.96 - 5.0 - 0.056), 1e-12);

  // A loaded map goes on with the gate as it was: narrow again after that hold.
  ExperienceMap loaded(config);
  loaded.Load(map.Save());
  const double before = loaded.RobotPose().theta;
  loaded.HoldHeading(0.28 - before);
  EXPECT_NEAR(loaded.RobotPose().theta, before, 1e-12);
  // A map file from before the gate was saved does not say how far its heading drifted: the gate
  // starts wide open.
  proto::ExperienceMap old_file = map.Save();
  old_file.clear_turned_since_hold_rad();
  loaded.Load(old_file);
  loaded.HoldHeading(0.28 - before);
  EXPECT_NEAR(loaded.RobotPose().theta, before - 0.056, 1e-12);

  ExpectKeysRefused(config, {{"exp_manhattan_min_offset_rad", [](ExperienceMapConfig& c) { c.exp_manhattan_min_offset_rad = 0; }},
                             {"exp_manhattan_offset_per_rad_turned",
                              [](ExperienceMapConfig& c) { c.exp_manhattan_offset_per_rad_turned = -0.1; }}});
}

// The robot drives straight along walls that lie on the map's axes (seen at 0 rad in the robot
// frame) while the odometry turns it 0.01 rad per experience: the least-squares correction, with
// the experiences' walls in it, takes most of that turn back out of the map. The robot's own hold
// is left out (a gain of 1e-9) to see the experiences' terms alone.
std::unique_ptr<ExperienceMap> DriftingAlongWalls(double sigma_rad, double wall_rad, bool taper = false) {
  ExperienceMapConfig config = LeastSquares(1);
  config.exp_manhattan_taper = taper;
  config.exp_initial_em_deg = 0;
  config.exp_manhattan = true;
  config.exp_manhattan_reference_frames = 5;
  config.exp_manhattan_gain = 1e-9;
  config.exp_manhattan_sigma_rad = sigma_rad;
  config.exp_graph_link_sigma_rad = 0.05;  // a long chain's turn is as unsure as this short one's
  auto map = std::make_unique<ExperienceMap>(config);
  map->Apply(Create(0, kNoExperience));
  for (int i = 0; i < 5; ++i) map->HoldHeading(0.0);  // the axes at 0; experience 0's wall too
  for (uint32_t id = 1; id <= 20; ++id) {
    map->Integrate(1.0, 0.01, 1.0);
    map->Apply(Create(id, id - 1));
    map->HoldHeading(wall_rad);
  }
  map->Apply(ExperienceAction{});
  return map;
}

TEST(ExperienceMap, LeastSquaresHoldsTheExperiencesToTheWalls) {
  const std::unique_ptr<ExperienceMap> free_map = DriftingAlongWalls(0.0, 0.0);
  const std::unique_ptr<ExperienceMap> held_map = DriftingAlongWalls(0.05, 0.0);
  const ExperienceMap& free = *free_map;
  const ExperienceMap& held = *held_map;
  // Each experience keeps the first wall seen at it, relative to its own facing: 0 where the
  // robot faced as the experience (no correction in between), without a correction.
  for (const Experience& e : free.experiences()) {
    ASSERT_TRUE(e.wall_rad.has_value()) << e.id;
    EXPECT_NEAR(*e.wall_rad, 0.0, 1e-12) << e.id;
  }
  // Without the terms nothing corrects the map: the last experience faces 0.2 rad, 2.1 m off the
  // line; with them -0.04 rad and 0.14 m.
  EXPECT_NEAR(free.experiences().back().th_rad, 0.2, 1e-6);
  EXPECT_GT(free.experiences().back().y_m, 2.0);
  EXPECT_LT(std::abs(held.experiences().back().th_rad), 0.05);
  EXPECT_LT(std::abs(held.experiences().back().y_m), 0.2);
  ASSERT_TRUE(held.manhattan_axes().has_value());
  EXPECT_NEAR(*held.manhattan_axes(), 0.0, 1e-12);

  // Walls 0.5 rad off the axes are other walls: the terms leave the map as the links have it.
  EXPECT_NEAR(DriftingAlongWalls(0.05, 0.5)->experiences().back().th_rad, 0.2, 1e-6);

  // The walls survive a save and a load; a map merged in without anchors keeps none (its frame
  // is its own, the axes are this map's).
  ExperienceMap loaded(held.config());
  loaded.Load(held.Save());
  EXPECT_EQ(loaded.experiences().back().wall_rad, held.experiences().back().wall_rad);
  proto::ExperienceMap bad = held.Save();
  bad.mutable_experiences(3)->set_wall_rad(std::numeric_limits<double>::infinity());
  EXPECT_THROW(loaded.Load(bad), std::invalid_argument);
  ExperienceMap merged(held.config());
  merged.Apply(Create(0, kNoExperience));
  merged.MergeFrom(held, {});
  EXPECT_FALSE(merged.experiences().back().wall_rad.has_value());

  ExperienceMapConfig negative = held.config();
  negative.exp_manhattan_sigma_rad = -0.1;
  try {
    negative.Validate();
    ADD_FAILURE() << "a negative exp_manhattan_sigma_rad was accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "exp_manhattan_sigma_rad");
  }
}

// exp_manhattan_taper: a wall's pull falls as its offset nears the widest gate, on the robot and in
// the least squares; one just inside it (a funnel's wall 0.24 rad off) barely turns anything.
TEST(ExperienceMap, AWallNearTheWidestGatePullsLessWithTheTaper) {
  EXPECT_DOUBLE_EQ(Taper(0.0, 0.25), 1.0);
  EXPECT_DOUBLE_EQ(Taper(-0.125, 0.25), 0.5625);
  EXPECT_DOUBLE_EQ(Taper(0.25, 0.25), 0.0);
  EXPECT_DOUBLE_EQ(Taper(-0.3, 0.25), 0.0);

  // Gain 0.2 of the offset, times the weight: 0.7056 at 0.1 rad, 0.00614656 at 0.24.
  for (const auto& [wall, plain_theta, tapered_theta] :
       {std::tuple{0.1, -0.02, -0.014112}, std::tuple{0.24, -0.048, -0.000295034880}}) {
    ExperienceMapConfig config = HeldToWalls();  // gain 0.2, widest gate 0.25
    ExperienceMap plain(config);
    config.exp_manhattan_taper = true;
    ExperienceMap tapered(config);
    for (ExperienceMap* map : {&plain, &tapered}) {
      for (int i = 0; i < 5; ++i) map->HoldHeading(0.0);  // the axes at 0
      map->HoldHeading(wall);
    }
    EXPECT_NEAR(plain.RobotPose().theta, plain_theta, 1e-12);
    EXPECT_NEAR(tapered.RobotPose().theta, tapered_theta, 1e-12);
  }

  // In the least squares the drift's walls (0-0.2 rad off as the map has them) still hold the
  // map: its last experience faces 0.2 rad without the terms, -0.041 with them, 0.007 tapered.
  EXPECT_NEAR(DriftingAlongWalls(0.0, 0.0)->experiences().back().th_rad, 0.2, 1e-6);
  EXPECT_NEAR(DriftingAlongWalls(0.05, 0.0)->experiences().back().th_rad, -0.041, 0.001);
  EXPECT_NEAR(DriftingAlongWalls(0.05, 0.0, true)->experiences().back().th_rad, 0.007, 0.001);
}

proto::ExperienceMap SmallGraph() {
  proto::ExperienceMap m;
  for (int i = 0; i < 5; ++i) m.add_experiences()->set_x_m(i);
  auto link = [&](uint32_t a, uint32_t b, double t) {
    auto* l = m.add_links();
    l->set_from_id(a);
    l->set_to_id(b);
    l->set_d_m(1.0);
    l->set_travel_time_s(t);
    l->set_traversals(1);
  };
  link(0, 1, 1.0);
  link(1, 2, 1.0);
  link(0, 3, 5.0);
  link(2, 3, 0.5);  // traversed backwards on the way 0 -> 3
  m.set_has_current(true);
  m.set_current_id(0);
  return m;
}

TEST(ExperienceMap, PathToGoalFollowsShortestTravelTimeOverLinks) {
  ExperienceMap map(ExperienceMapConfig{});
  map.Load(SmallGraph());
  EXPECT_EQ(map.PathToGoal(0, 3), (std::vector<uint32_t>{0, 1, 2, 3}));  // 2.5 s < 5 s
  EXPECT_EQ(map.PathToGoal(3, 0), (std::vector<uint32_t>{3, 2, 1, 0}));
  EXPECT_EQ(map.PathToGoal(2, 2), (std::vector<uint32_t>{2}));
  EXPECT_TRUE(map.PathToGoal(0, 4).empty());  // 4 has no links
  EXPECT_THROW(map.PathToGoal(0, 9), std::invalid_argument);
}

TEST(ExperienceMap, SaveLoadRoundTripContinuesIdentically) {
  ExperienceMapConfig cfg;
  cfg.exp_relax_budget_links = 7;
  ExperienceMap a(cfg);
  DriveSquare(a, 1.02, 0.01);
  a.Integrate(0.3, 0.05, 1.0);
  ExperienceMap b(cfg);
  b.Load(a.Save());
  EXPECT_EQ(b.Save().SerializeAsString(), a.Save().SerializeAsString());
  for (int i = 0; i < 50; ++i) {
    a.Apply(ExperienceAction{});
    b.Apply(ExperienceAction{});
  }
  a.Apply(LinkTo(Kind::kSet, 0, 1));
  b.Apply(LinkTo(Kind::kSet, 0, 1));
  EXPECT_EQ(b.Save().SerializeAsString(), a.Save().SerializeAsString());
}

TEST(ExperienceMap, MergeOffsetsIdsAndAnchorsTheSecondMap) {
  ExperienceMap a(NoCorrection());
  a.Apply(Create(0, kNoExperience));
  a.Integrate(1.0, 0.0, 3.0);
  a.Apply(Create(1, 0));  // (0, 3) facing +y
  ExperienceMapConfig b_cfg = NoCorrection();
  b_cfg.exp_initial_em_deg = 0.0;  // b's frame is turned 90 degrees from a's
  ExperienceMap b(b_cfg);
  b.Apply(Create(0, kNoExperience));
  b.Integrate(2.0, 0.0, 1.0);  // along b's x
  b.Apply(Create(1, 0));
  b.Integrate(1.0, 0.0, 1.0);
  b.Apply(Create(2, 1));
  const size_t a_links = a.links().size();
  a.MergeFrom(b, {{1, 0}});  // b's experience 0 is a's experience 1
  ASSERT_EQ(a.experiences().size(), 5u);
  EXPECT_EQ(a.links().size(), a_links + b.links().size() + 1);
  const Experience& b0 = a.experiences()[2];
  EXPECT_NEAR(b0.x_m, 0.0, 1e-9);
  EXPECT_NEAR(b0.y_m, 3.0, 1e-9);
  EXPECT_NEAR(b0.th_rad, kPi / 2, 1e-9);
  // b's first move was along its own facing: now along a's +y.
  EXPECT_NEAR(a.experiences()[3].x_m, 0.0, 1e-9);
  EXPECT_NEAR(a.experiences()[3].y_m, 5.0, 1e-9);
  const Link& anchor = a.links().back();
  EXPECT_EQ(anchor.from_id, 1u);
  EXPECT_EQ(anchor.to_id, 2u);
  EXPECT_EQ(a.links()[a_links].from_id, 2u);  // b's 0 -> 1, offset by 2
  EXPECT_EQ(a.links()[a_links].to_id, 3u);
  EXPECT_EQ(a.current_id(), 1u);
  EXPECT_FALSE(a.PathToGoal(0, 4).empty());
  ExperienceMap reloaded(NoCorrection());
  reloaded.Load(a.Save());
  EXPECT_EQ(reloaded.Save().SerializeAsString(), a.Save().SerializeAsString());
  EXPECT_THROW(a.MergeFrom(b, {{9, 0}}), std::invalid_argument);
}

TEST(ExperienceMap, CorruptMapFileIsRefused) {
  ExperienceMap map(NoCorrection());
  DriveSquare(map, 1.0, 0.0);
  const std::string path = ::testing::TempDir() + "/rslam_experience_map_corrupt_test.pb";
  WriteStateFile(path, "rslam.experience_map.ExperienceMap", 1, map.Save());
  proto::ExperienceMap ok;
  ReadStateFile(path, "rslam.experience_map.ExperienceMap", 1, ok);
  EXPECT_EQ(ok.experiences_size(), 20);
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(-10, std::ios::end);
    char c;
    f.read(&c, 1);
    c = static_cast<char>(c ^ 0x5a);
    f.seekp(-10, std::ios::end);
    f.write(&c, 1);
  }
  proto::ExperienceMap bad;
  EXPECT_THROW(ReadStateFile(path, "rslam.experience_map.ExperienceMap", 1, bad), StateFileError);
  std::filesystem::remove(path);
}

TEST(ExperienceMap, LoadRefusesInconsistentMessage) {
  ExperienceMap map(NoCorrection());
  proto::ExperienceMap m = SmallGraph();
  m.mutable_links(0)->set_to_id(42);
  EXPECT_THROW(map.Load(m), std::invalid_argument);
  m = SmallGraph();
  m.mutable_experiences(1)->set_x_m(std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW(map.Load(m), std::invalid_argument);
  EXPECT_TRUE(map.experiences().empty());
}

TEST(ExperienceMap, RejectsInconsistentIdsAndNonFiniteOdometry) {
  ExperienceMap map(NoCorrection());
  EXPECT_THROW(map.Apply(Create(1, kNoExperience)), std::invalid_argument);  // not the next id
  map.Apply(Create(0, kNoExperience));
  map.Integrate(1.0, 0.0, 1.0);
  map.Apply(Create(1, 0));
  const std::string before = map.Save().SerializeAsString();
  EXPECT_THROW(map.Apply(Create(3, 1)), std::invalid_argument);        // gap in ids
  EXPECT_THROW(map.Apply(Create(2, 0)), std::invalid_argument);        // from is not current
  EXPECT_THROW(map.Apply(LinkTo(Kind::kLink, 1, 7)), std::invalid_argument);  // unknown id
  EXPECT_THROW(map.Apply(LinkTo(Kind::kSet, 1, 9)), std::invalid_argument);
  EXPECT_THROW(map.Apply(LinkTo(Kind::kLink, 1, 1)), std::invalid_argument);  // self link
  ExperienceAction nan_angle = LinkTo(Kind::kSet, 1, 0);
  nan_angle.relative_angle_rad = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(map.Apply(nan_angle), std::invalid_argument);
  ExperienceAction nan_offset = LinkTo(Kind::kSet, 1, 0);
  nan_offset.offset_x_m = std::numeric_limits<double>::infinity();
  EXPECT_THROW(map.Apply(nan_offset), std::invalid_argument);
  EXPECT_THROW(map.Integrate(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(map.Integrate(1.0, std::numeric_limits<double>::infinity(), 0.1), std::invalid_argument);
  EXPECT_THROW(map.Integrate(1.0, 0.0, -0.1), std::invalid_argument);
  EXPECT_EQ(map.Save().SerializeAsString(), before);
}

}  // namespace
}  // namespace rslam::experience_map
