#include "services/occupancy/profile_alignment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "services/occupancy/anchored_profile_map.h"
#include "services/occupancy/occupancy_node_config.h"
#include "tests/unit/occupancy/synthetic_scene.h"

namespace rslam::occupancy {
namespace {

using testing::RayHitsSegment;
using testing::Wall;

// A room corner with a pillar in it: walls x = 2 and y = 1.5, and a 0.3 m square pillar at (1.2, 0.9)
// that pins the pose down along both walls. Seen from around (0.5, 0).
const std::vector<Wall> kScene = {
    {{2.0, -2.0}, {2.0, 1.5}}, {{-2.0, 1.5}, {2.0, 1.5}},
    {{1.05, 0.75}, {1.35, 0.75}}, {{1.35, 0.75}, {1.35, 1.05}}, {{1.35, 1.05}, {1.05, 1.05}}, {{1.05, 1.05}, {1.05, 0.75}}};

// The 60-degree, 1-degree-bin profile a camera at `pose` takes of the scene (2 m scan range).
RadialObstacleProfile ProfileAt(const Pose2D& pose, const std::vector<Wall>& scene = kScene) {
  RadialObstacleProfile p;
  p.bin_width_rad = M_PI / 180.0;
  p.first_bearing_rad = -30 * p.bin_width_rad;
  for (int i = 0; i < 60; ++i) {
    const double bearing = pose.theta + p.BinCentre(i);
    double range = 2.0;
    for (const Wall& w : scene)
      if (auto d = RayHitsSegment({pose.x, pose.y}, std::cos(bearing), std::sin(bearing), w)) range = std::min(range, *d);
    p.bins.push_back(RopBin{static_cast<float>(range), 0.35f, range < 2.0 ? BinStatus::kObstacle : BinStatus::kFree});
  }
  return p;
}

// The corner seen from a dozen poses, three times over.
std::vector<Pose2D> SeenFrom() {
  std::vector<Pose2D> poses;
  for (int pass = 0; pass < 3; ++pass)
    for (int i = 0; i < 12; ++i) poses.push_back({0.3 + 0.05 * i, -0.2 + 0.04 * i, 0.3 + 0.08 * i});
  return poses;
}

// A 10 m grid of `resolution` cells around the corner.
GridConfig GridOf(double resolution) {
  const int cells = static_cast<int>(std::lround(10.0 / resolution));
  return GridConfig{resolution, cells, cells, -5.0, -5.0};
}

OccupancyGrid SeenGrid(double resolution) {
  SensorModelConfig sensor;
  sensor.reliable_range_m = 1.5;
  OccupancyGrid grid(GridOf(resolution), sensor);
  for (const Pose2D& seen : SeenFrom()) grid.InsertProfile(ProfileAt(seen), seen);
  return grid;
}

ProfileAlignmentConfig On() {
  ProfileAlignmentConfig c;
  c.window_m = 0.3;
  return c;
}

// On the 0.05-m cells the search was tuned on and on the demo's 0.025-m ones (its steps, field and
// reach are in cells: finer cells search finer).
class ProfileAlignmentOnCellsOf : public ::testing::TestWithParam<double> {};
INSTANTIATE_TEST_SUITE_P(Metres, ProfileAlignmentOnCellsOf, ::testing::Values(0.05, 0.025));

TEST_P(ProfileAlignmentOnCellsOf, AProfileDrawnOffTheWallsSeenBeforeIsMovedBackOntoThem) {
  const OccupancyGrid grid = SeenGrid(GetParam());
  const Pose2D truth{0.7, 0.1, 0.75};
  const RadialObstacleProfile profile = ProfileAt(truth);
  // The map puts the robot 0.2 m off and turned 0.05 rad: its walls would land on seen floor.
  for (const Pose2D& error : {Pose2D{-0.15, -0.12, 0.05}, Pose2D{0.1, -0.17, -0.04}, Pose2D{-0.2, 0.05, 0.0}}) {
    const Pose2D placed{truth.x + error.x, truth.y + error.y, truth.theta + error.theta};
    const std::optional<Pose2D> aligned = AlignProfile(grid, profile, placed, On());
    ASSERT_TRUE(aligned.has_value()) << error.x << " " << error.y;
    EXPECT_LT(std::hypot(aligned->x - truth.x, aligned->y - truth.y), 0.05) << aligned->x << " " << aligned->y;
    // Turns are found to the grid's grain: a cell (5 cm) at 1.1 m.
    EXPECT_LT(std::abs(aligned->theta - truth.theta), 0.045) << aligned->theta;
  }
  // Off, or where it was taken, it stays.
  EXPECT_FALSE(AlignProfile(grid, profile, {truth.x - 0.15, truth.y - 0.12, truth.theta}, ProfileAlignmentConfig{}));
  EXPECT_FALSE(AlignProfile(grid, profile, truth, On()));
  // Beyond the window it is not found.
  ProfileAlignmentConfig narrow = On();
  narrow.window_m = 0.05;
  narrow.window_rad = 0.0;
  const std::optional<Pose2D> near = AlignProfile(grid, profile, {truth.x - 0.2, truth.y, truth.theta}, narrow);
  if (near) {
    EXPECT_GT(std::abs(near->x - truth.x), 0.14);
  }
}

TEST(ProfileAlignmentTest, AProfileOfAPlaceNotSeenBeforeIsNotMovedOntoOtherWalls) {
  const OccupancyGrid grid = SeenGrid(0.05);
  // Facing away from the corner at a wall the grid has not seen (x = -0.6): its points fall on
  // unknown cells, however far off the map may have put it.
  const std::vector<Wall> other = {{{-0.6, -2.0}, {-0.6, 2.0}}};
  const Pose2D truth{0.6, 0.4, M_PI};
  const RadialObstacleProfile profile = ProfileAt(truth, other);
  EXPECT_FALSE(AlignProfile(grid, profile, truth, On()));
  EXPECT_FALSE(AlignProfile(grid, profile, {truth.x + 0.2, truth.y, truth.theta}, On()));
  // Too few obstacle points pin nothing down.
  RadialObstacleProfile few = ProfileAt({0.7, 0.1, 0.75});
  few.bins.resize(8);
  EXPECT_FALSE(AlignProfile(grid, few, {0.55, 0.0, 0.8}, On()));
}

TEST_P(ProfileAlignmentOnCellsOf, ARebuildAlignsAMisplacedProfileAndSearchesAgainOnlyWhereItMoved) {
  SensorModelConfig sensor;
  sensor.reliable_range_m = 1.5;
  const GridConfig grid = GridOf(GetParam());
  const Pose2D truth{0.7, 0.1, 0.75}, placed{0.55, -0.02, 0.8};
  const auto fill = [&](AnchoredProfileMap& map) {
    for (const Pose2D& seen : SeenFrom()) map.AddProfile(1, {0, 0, 0}, seen, ProfileAt(seen));
    map.AddProfile(2, {0, 0, 0}, placed, ProfileAt(truth));  // taken at `truth`, the map says `placed`
  };
  const auto drawn = [](const AnchoredProfile& p) {
    return Compose(Compose(p.experience_pose, p.offset), p.alignment.correction);
  };
  const auto keep = [](uint64_t) -> std::optional<Pose2D> { return std::nullopt; };

  AnchoredProfileMap as_drawn(grid, sensor);
  fill(as_drawn);
  as_drawn.Rebuild(keep);
  EXPECT_EQ(as_drawn.AlignedProfiles(), 0u);

  AnchoredProfileMap map(grid, sensor, On());
  fill(map);
  EXPECT_EQ(map.AlignedProfiles(), 0u);  // new profiles join as the map puts them
  map.Rebuild(keep);
  EXPECT_EQ(map.AlignedProfiles(), 1u);
  const Pose2D first = drawn(map.profiles().back());
  EXPECT_LT(std::hypot(first.x - truth.x, first.y - truth.y), 0.05);
  // As the map put it, its nearest obstacle point lands on seen floor; aligned, that floor takes no hit.
  std::vector<Eigen::Vector2d> points;
  ProfileAt(truth).ObstaclePoints(points);
  const Eigen::Vector2d nearest = *std::min_element(
      points.begin(), points.end(), [](const auto& a, const auto& b) { return a.norm() < b.norm(); });
  const Eigen::Vector2d hit = nearest * map.grid().HitRange(nearest.norm()) / nearest.norm();
  const Pose2D short_wall = Compose(placed, {hit.x(), hit.y(), 0.0});
  const CellIndex twice = map.grid().CellOf(short_wall.x, short_wall.y);
  EXPECT_GT(as_drawn.grid().LogOdds(twice), map.grid().LogOdds(twice) + 0.5);

  map.Rebuild(keep);  // nothing moved: the same correction
  EXPECT_EQ(map.AlignedProfiles(), 1u);
  EXPECT_EQ(drawn(map.profiles().back()).x, first.x);
  // The map moves experience 2 by less than a cell: not searched again.
  const auto moved_by = [](double dx) {
    return [dx](uint64_t id) { return id == 2 ? std::optional<Pose2D>(Pose2D{dx, 0.0, 0.0}) : std::nullopt; };
  };
  map.Rebuild(moved_by(0.8 * GetParam()));
  EXPECT_EQ(map.profiles().back().alignment.searched_from->x, placed.x);
  // The map corrects experience 2 by 10 cm: searched again from there, drawn where it was taken.
  map.Rebuild(moved_by(0.1));
  const Pose2D again = drawn(map.profiles().back());
  EXPECT_EQ(map.profiles().back().alignment.searched_from->x, placed.x + 0.1);
  EXPECT_LT(std::hypot(again.x - truth.x, again.y - truth.y), 0.05);
}

TEST(ProfileAlignmentTest, BadSettingsAreRefusedByName) {
  for (const auto& [key, value] : std::vector<std::pair<std::string, double>>{
           {"window_m", -0.1}, {"window_rad", 2.0}, {"match_range_m", 0.0}, {"min_misplaced_share", 0.0},
           {"min_gain_points", -1.0}}) {
    OccupancyNodeConfig config;
    ProfileAlignmentConfig& a = config.profile_alignment;
    if (key == "window_m") a.window_m = value;
    if (key == "window_rad") a.window_rad = value;
    if (key == "match_range_m") a.match_range_m = value;
    if (key == "min_misplaced_share") a.min_misplaced_share = value;
    if (key == "min_gain_points") a.min_gain_points = value;
    try {
      config.Validate();
      ADD_FAILURE() << key << " = " << value << " was accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("profile_alignment." + key), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace rslam::occupancy
