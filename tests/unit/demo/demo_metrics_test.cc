// The demo's figures of merit (tools/demo/demo_metrics.h): the grid against the world (coverage,
// precision and where each is lost, and grid_errors.png that shows it), placing a map in the world,
// and the final map's trajectory error.

#include "tools/demo/demo_metrics.h"
#include "tools/demo/demo_artifacts.h"

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

// A 1.2 m square room at 0.1 m cells: walls two cells thick, 8 x 8 free cells inside.
sim::WorldMap SquareRoom() {
  std::vector<sim::CellClass> cells(12 * 12, sim::CellClass::kOccupied);
  for (int iy = 2; iy < 10; ++iy)
    for (int ix = 2; ix < 10; ++ix) cells[iy * 12 + ix] = sim::CellClass::kFree;
  return sim::WorldMap(12, 12, 0.1, {0.0, 0.0}, std::move(cells));
}

// The room as a grid would map it, in a map frame whose origin lies at `map_origin` in the
// world (translation only), with a few cells changed.
msg::OccupancyGrid RoomGrid(const sim::WorldMap& world, const Eigen::Vector2d& map_origin,
                            const std::map<std::pair<int, int>, int8_t>& changed) {
  msg::OccupancyGrid grid{};
  grid.width = grid.height = 12;
  grid.resolution_m = 0.1f;
  grid.origin_x_m = -map_origin.x();
  grid.origin_y_m = -map_origin.y();
  for (int iy = 0; iy < 12; ++iy)
    for (int ix = 0; ix < 12; ++ix) {
      const auto it = changed.find({ix, iy});
      grid.cells.push_back(it != changed.end() ? it->second
                           : world.Classify({ix, iy}) == sim::CellClass::kFree ? int8_t{0}
                                                                                : int8_t{100});
    }
  return grid;
}

TEST(DemoMetricsTest, CompareGridWithWorldCountsWhereCoverageAndPrecisionAreLost) {
  const sim::WorldMap world = SquareRoom();
  const Pose2D start{0.55, 0.55, 0.0};
  const std::vector<Eigen::Vector2i> reachable = ReachableFootprint(world, start, 0.0);
  ASSERT_EQ(reachable.size(), 64u);
  const std::map<std::pair<int, int>, int8_t> changed = {
      {{3, 3}, -1}, {{3, 4}, -1},  // never seen
      {{6, 6}, 50},                // between the thresholds
      {{5, 5}, 100},               // occupied, a cell from any wall: missed and wrong
      {{0, 6}, 0},                 // free inside the wall, no floor within a cell: wrong
      {{2, 6}, 100},               // occupied next to the wall: missed, but within the tolerance
  };
  // The same grid placed by the map origin, wherever the map frame starts.
  for (const Eigen::Vector2d& origin : {Eigen::Vector2d(0, 0), Eigen::Vector2d(0.6, 0.6)}) {
    SCOPED_TRACE(origin.transpose());
    const GridComparison c = CompareGridWithWorld(world, reachable, {origin.x(), origin.y(), 0.0},
                                                  RoomGrid(world, origin, changed), world.resolution());
    EXPECT_EQ(c.reachable_cells, 64u);
    EXPECT_EQ(c.covered_cells, 59u);
    EXPECT_EQ(c.missed_unknown_cells, 2u);
    EXPECT_EQ(c.missed_uncertain_cells, 1u);
    EXPECT_EQ(c.missed_occupied_cells, 2u);
    EXPECT_DOUBLE_EQ(c.coverage, 59.0 / 64.0);
    EXPECT_EQ(c.marked_cells, 144u - 3u);
    EXPECT_EQ(c.wrong_free_cells, 1u);
    EXPECT_EQ(c.wrong_occupied_cells, 1u);
    EXPECT_EQ(c.agreeing_cells, 141u - 2u);
    EXPECT_DOUBLE_EQ(c.precision, 139.0 / 141.0);
  }
}

TEST(DemoMetricsTest, GridComparisonPictureColoursEachCellAsTheCountsJudgeIt) {
  const sim::WorldMap world = SquareRoom();
  const std::vector<Eigen::Vector2i> reachable = ReachableFootprint(world, {0.55, 0.55, 0.0}, 0.0);
  const std::map<std::pair<int, int>, int8_t> changed = {
      {{3, 3}, -1}, {{6, 6}, 50}, {{5, 5}, 100}, {{0, 6}, 0}, {{1, 1}, 0}, {{11, 4}, -1}};
  const Eigen::Vector2d origin(0.6, 0.6);
  const cv::Mat image = RenderGridComparison(world, reachable, {origin.x(), origin.y(), 0.0},
                                             RoomGrid(world, origin, changed), world.resolution());
  // The reachable cells (2..9) and 1 m (10 cells) around them, each cell zoom pixels, under a
  // 40-pixel legend; the first row is the largest y.
  const int cells = 8 + 2 * 10, zoom = 1000 / cells;
  ASSERT_EQ(image.cols, cells * zoom);
  ASSERT_EQ(image.rows, 40 + cells * zoom);
  auto at = [&](int ix, int iy) {
    return image.at<cv::Vec3b>(40 + (9 + 10 - iy) * zoom + zoom / 2, (ix - 2 + 10) * zoom + zoom / 2);
  };
  EXPECT_EQ(at(4, 4), cv::Vec3b(255, 255, 255));  // covered
  EXPECT_EQ(at(3, 3), cv::Vec3b(0, 150, 255));    // unknown
  EXPECT_EQ(at(6, 6), cv::Vec3b(0, 215, 255));    // uncertain
  EXPECT_EQ(at(5, 5), cv::Vec3b(40, 40, 220));    // occupied
  EXPECT_EQ(at(0, 6), cv::Vec3b(220, 120, 0));    // free on a wall, no floor within the tolerance
  EXPECT_EQ(at(1, 1), cv::Vec3b(150, 150, 150));  // free on a wall beside the floor: agrees, a wall not marked
  EXPECT_EQ(at(0, 0), cv::Vec3b(0, 0, 0));        // a wall the grid marks occupied
  EXPECT_EQ(at(11, 4), cv::Vec3b(150, 150, 150)); // a wall the grid has not seen
  EXPECT_EQ(at(-3, -3), cv::Vec3b(150, 150, 150)); // outside the world and the grid
}

TEST(DemoMetricsTest, CompareGridWithWorldCountsTheWorldOutsideTheGridAsUnknown) {
  const sim::WorldMap world = SquareRoom();
  const std::vector<Eigen::Vector2i> reachable = ReachableFootprint(world, {0.55, 0.55, 0.0}, 0.0);
  // The map frame half a metre to the right of the grid's world: the room's three left columns of
  // floor fall outside the grid.
  const GridComparison c = CompareGridWithWorld(world, reachable, {0.5, 0.0, 0.0},
                                                RoomGrid(world, {0.0, 0.0}, {}), world.resolution());
  EXPECT_EQ(c.missed_unknown_cells, 3u * 8u);
  EXPECT_EQ(c.covered_cells + c.missed_unknown_cells + c.missed_uncertain_cells + c.missed_occupied_cells, 64u);
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

TEST(DemoMetricsTest, CheckLoopClosuresListsTheWrongOnes) {
  const std::map<uint32_t, Pose2D> truth = {{1, {0, 0, 0}}, {2, {0.5, 0, 0}}, {3, {3, 4, 0}}};
  std::vector<msg::ExperienceLink> links(4);
  links[0].from_id = 2, links[0].to_id = 1, links[0].closes_loop = true;  // 0.5 m apart: right
  links[1].from_id = 3, links[1].to_id = 1, links[1].closes_loop = true;  // 5 m apart: wrong
  links[2].from_id = 3, links[2].to_id = 2, links[2].closes_loop = false; // odometry: not judged
  links[3].from_id = 9, links[3].to_id = 1, links[3].closes_loop = true;  // no ground truth
  const LoopClosureCheck c = CheckLoopClosures(links, truth, 1.0);
  EXPECT_EQ(c.links, 4u);
  EXPECT_EQ(c.loop_closures, 3u);
  EXPECT_EQ(c.verified, 2u);
  EXPECT_EQ(c.correct, 1u);
  ASSERT_TRUE(c.precision.has_value());
  EXPECT_DOUBLE_EQ(*c.precision, 0.5);
  ASSERT_EQ(c.wrong.size(), 1u);
  EXPECT_EQ(c.wrong[0].from_id, 3u);
  EXPECT_EQ(c.wrong[0].to_id, 1u);
  EXPECT_DOUBLE_EQ(c.wrong[0].distance_m, 5.0);
  ASSERT_TRUE(c.farthest_m.has_value());
  EXPECT_DOUBLE_EQ(*c.farthest_m, 5.0);
}

TEST(DemoMetricsTest, TheFarthestLoopClosureIsTheMarginEvenWhenAllAreRight) {
  const std::map<uint32_t, Pose2D> truth = {{1, {0, 0, 0}}, {2, {0.3, 0.4, 0}}, {3, {0.9, 0, 0}}};
  std::vector<msg::ExperienceLink> links(3);
  links[0].from_id = 2, links[0].to_id = 1, links[0].closes_loop = true;   // 0.5 m
  links[1].from_id = 3, links[1].to_id = 1, links[1].closes_loop = true;   // 0.9 m
  links[2].from_id = 3, links[2].to_id = 2, links[2].closes_loop = false;  // odometry: 0.72 m, not judged
  const LoopClosureCheck c = CheckLoopClosures(links, truth, 1.0);
  EXPECT_EQ(c.wrong.size(), 0u);
  ASSERT_TRUE(c.farthest_m.has_value());
  EXPECT_DOUBLE_EQ(*c.farthest_m, 0.9);
  EXPECT_FALSE(CheckLoopClosures({}, truth, 1.0).farthest_m.has_value());
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
