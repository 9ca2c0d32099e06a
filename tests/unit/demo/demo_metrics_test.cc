// The demo's figures of merit (tools/demo/demo_metrics.h): placing a map in the world, and the
// final map's trajectory error.

#include "tools/demo/demo_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <vector>

namespace rslam::demo {
namespace {

msg::Experience At(uint32_t id, double x, double y) {
  msg::Experience e{};
  e.id = id;
  e.x_m = x;
  e.y_m = y;
  return e;
}

TEST(DemoMetricsTest, FitMapToWorldRecoversATurnedAndShiftedMap) {
  // World positions of four experiences; the map holds them turned by 0.4 rad and shifted.
  const std::map<uint32_t, Pose2D> truth = {
      {0, {1.0, 2.0, 0.0}}, {1, {3.0, 2.5, 0.0}}, {2, {2.0, -1.0, 0.0}}, {5, {-1.0, 0.5, 0.0}}};
  const Pose2D map_to_world{0.7, -0.3, 0.4};
  std::vector<msg::Experience> map;
  const double c = std::cos(-map_to_world.theta), s = std::sin(-map_to_world.theta);
  for (const auto& [id, w] : truth) {
    const double dx = w.x - map_to_world.x, dy = w.y - map_to_world.y;
    map.push_back(At(id, c * dx - s * dy, s * dx + c * dy));
  }
  map.push_back(At(9, 50.0, 50.0));  // no ground truth: ignored
  const auto fit = FitMapToWorld(map, truth);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->x, map_to_world.x, 1e-9);
  EXPECT_NEAR(fit->y, map_to_world.y, 1e-9);
  EXPECT_NEAR(fit->theta, map_to_world.theta, 1e-9);
  for (const auto& e : map) {
    if (!truth.count(e.id)) continue;
    const Pose2D w = MapToWorld(*fit, e.x_m, e.y_m);
    EXPECT_NEAR(w.x, truth.at(e.id).x, 1e-9);
    EXPECT_NEAR(w.y, truth.at(e.id).y, 1e-9);
  }
}

TEST(DemoMetricsTest, FitMapToWorldIsTheLeastSquaresTurnOfANoisyMap) {
  // Symmetric errors around the true positions leave the fit at the identity.
  const std::map<uint32_t, Pose2D> truth = {{0, {0, 0, 0}}, {1, {2, 0, 0}}, {2, {2, 2, 0}}, {3, {0, 2, 0}}};
  const std::vector<msg::Experience> map = {At(0, 0.1, 0), At(1, 1.9, 0), At(2, 2.1, 2), At(3, -0.1, 2)};
  const auto fit = FitMapToWorld(map, truth);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->theta, 0.0, 1e-9);
  EXPECT_NEAR(fit->x, 0.0, 1e-9);
  EXPECT_NEAR(fit->y, 0.0, 1e-9);
}

TEST(DemoMetricsTest, FitMapToWorldNeedsTwoExperiencesWithGroundTruth) {
  const std::map<uint32_t, Pose2D> truth = {{0, {1.0, 2.0, 0.0}}};
  const std::vector<msg::Experience> map = {At(0, 0, 0), At(1, 1, 0)};
  EXPECT_FALSE(FitMapToWorld(map, truth).has_value());
}

TEST(DemoMetricsTest, MapOriginTurnsTheMapByItsInitialFacing) {
  // The robot starts at (1, 2) facing 0.3 rad in the world; the experience map has it facing
  // pi/2 (OpenRatSLAM's default). A point 1 m ahead of the start in the map, (0, 1), is 1 m ahead
  // in the world.
  const Pose2D start{1.0, 2.0, 0.3};
  const Pose2D ahead = MapToWorld(MapOrigin(start, std::numbers::pi / 2), 0.0, 1.0);
  EXPECT_NEAR(ahead.x, 1.0 + std::cos(0.3), 1e-12);
  EXPECT_NEAR(ahead.y, 2.0 + std::sin(0.3), 1e-12);
  // Facing 0 in the map: the map frame is the start pose's own.
  const Pose2D same = MapToWorld(MapOrigin(start, 0.0), 1.0, 0.0);
  EXPECT_NEAR(same.x, 1.0 + std::cos(0.3), 1e-12);
  EXPECT_NEAR(same.y, 2.0 + std::sin(0.3), 1e-12);
}

// Ground truth of frames 0..9 on an L-shaped path, stamped 100 ms apart.
DemoObservations LPath() {
  DemoObservations seen;
  for (uint64_t f = 0; f < 10; ++f) {
    const double x = f < 5 ? f * 1.0 : 4.0, y = f < 5 ? 0.0 : (f - 4) * 1.0;
    seen.ground_truth.push_back({f, static_cast<int64_t>(f) * 100'000'000, x, y, 0.0});
  }
  return seen;
}

TEST(DemoMetricsTest, ExperienceMapTrajectoryJudgesWhereTheFinalMapPutsEachExperience) {
  DemoObservations seen = LPath();
  // Experiences first current at frames 0, 3, 6 and 9; one never current (ignored), one current at
  // a frame without ground truth (ignored).
  seen.experience_first_frame = {{10, 0}, {11, 3}, {12, 6}, {13, 9}, {15, 42}};
  msg::ExperienceMap map{};
  // The final map holds them at half scale, turned a quarter turn: a similarity of the truth.
  for (const auto& [id, frame] : seen.experience_first_frame) {
    if (frame >= seen.ground_truth.size()) {
      map.experiences.push_back(At(id, 9.0, 9.0));
      continue;
    }
    const FramePose& t = seen.ground_truth[frame];
    map.experiences.push_back(At(id, -0.5 * t.y, 0.5 * t.x));
  }
  map.experiences.push_back(At(14, 7.0, 7.0));
  const std::vector<FramePose> trajectory = ExperienceMapTrajectory(map, seen);
  ASSERT_EQ(trajectory.size(), 4u);
  for (size_t i = 0; i < trajectory.size(); ++i) {
    EXPECT_EQ(trajectory[i].frame_seq, 3 * i);
    EXPECT_EQ(trajectory[i].stamp_ns, seen.ground_truth[3 * i].stamp_ns);
  }
  const auto error = TrajectoryErrorAgainstTruth(trajectory, seen.ground_truth);
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(error->pairs, 4u);
  EXPECT_NEAR(error->ate_m, 0.0, 1e-9);
  EXPECT_NEAR(error->scale, 2.0, 1e-9);

  // Moving one experience in the final map is what the error sees.
  map.experiences[1].x_m += 1.0;
  EXPECT_GT(TrajectoryErrorAgainstTruth(ExperienceMapTrajectory(map, seen), seen.ground_truth)->ate_m, 0.1);
}

TEST(DemoMetricsTest, AtFramesComparesTheOdometryAtTheExperiencesFrames) {
  const DemoObservations seen = LPath();
  // Odometry exact at frames 0, 3, 6, 9 and 1 m off at the others.
  std::vector<FramePose> odometry = seen.ground_truth;
  for (auto& p : odometry)
    if (p.frame_seq % 3 != 0) p.y += 1.0;
  const std::vector<FramePose> experiences = {seen.ground_truth[0], seen.ground_truth[3], seen.ground_truth[6],
                                              seen.ground_truth[9]};
  const std::vector<FramePose> sampled = AtFrames(odometry, experiences);
  ASSERT_EQ(sampled.size(), 4u);
  EXPECT_EQ(sampled[2].frame_seq, 6u);
  EXPECT_NEAR(TrajectoryErrorAgainstTruth(sampled, seen.ground_truth)->ate_m, 0.0, 1e-9);
  EXPECT_GT(TrajectoryErrorAgainstTruth(odometry, seen.ground_truth)->ate_m, 0.3);
}

}  // namespace
}  // namespace rslam::demo
