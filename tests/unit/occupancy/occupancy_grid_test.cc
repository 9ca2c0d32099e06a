#include "services/occupancy/occupancy_grid.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "services/occupancy/grid_export.h"

namespace rslam::occupancy {
namespace {

// A 10 x 10 grid of 10 cm cells with its origin at (0, 0); the robot stands in cell (2, 5).
GridConfig SmallGrid() { return GridConfig{0.1, 10, 10, 0.0, 0.0}; }
SensorModelConfig Model(double reliable = 0.6) {
  SensorModelConfig m;
  m.reliable_range_m = reliable;
  return m;
}
// One bin pointing along +x (bearing 0) with the given status and range.
RadialObstacleProfile OneBin(BinStatus status, float range, float nearest_visible = 0.0f) {
  RadialObstacleProfile p;
  p.first_bearing_rad = -0.005;
  p.bin_width_rad = 0.01;
  p.bins.push_back(RopBin{range, nearest_visible, status});
  return p;
}
const Pose2D kRobot{0.25, 0.55, 0.0};

TEST(OccupancyGridTest, ObstacleRayMarksFreeCellsThenOneHit) {
  OccupancyGrid grid(SmallGrid(), Model());
  const int64_t updates = grid.InsertProfile(OneBin(BinStatus::kObstacle, 0.38f), kRobot);
  // From x = 0.25 to the wall's face at x = 0.63: cells 2..5 free, cell 6 (mostly wall) occupied,
  // all in row 5.
  EXPECT_EQ(updates, 5);
  const double miss = LogOddsFromProbability(0.4), hit = LogOddsFromProbability(0.7);
  for (int x = 2; x <= 5; ++x) EXPECT_NEAR(grid.LogOdds({x, 5}), miss, 1e-3) << x;
  EXPECT_NEAR(grid.LogOdds({6, 5}), hit, 1e-3);
  EXPECT_GT(grid.Probability({6, 5}), 0.69);
  for (int x : {0, 1, 7, 8, 9}) EXPECT_FALSE(grid.IsKnown({x, 5})) << x;
  for (int y : {4, 6}) EXPECT_FALSE(grid.IsKnown({4, y}));
}

TEST(OccupancyGridTest, TheHitGoesToTheCellThatHoldsMoreWallThanFloor) {
  // A face at x = 0.68 lies in cell 6's far half: cell 6 is mostly floor, cell 7 mostly wall.
  OccupancyGrid grid(SmallGrid(), Model());
  grid.InsertProfile(OneBin(BinStatus::kObstacle, 0.43f), kRobot);
  for (int x = 2; x <= 6; ++x) EXPECT_LT(grid.Probability({x, 5}), 0.5) << x;
  EXPECT_GT(grid.Probability({7, 5}), 0.69);
  EXPECT_FALSE(grid.IsKnown({8, 5}));
  // At x = 0.62, its near half: cell 6 holds the wall.
  OccupancyGrid near(SmallGrid(), Model());
  near.InsertProfile(OneBin(BinStatus::kObstacle, 0.37f), kRobot);
  EXPECT_GT(near.Probability({6, 5}), 0.69);
  EXPECT_FALSE(near.IsKnown({7, 5}));
}

TEST(OccupancyGridTest, IgnoresObstaclesBeyondReliableRange) {
  OccupancyGrid grid(SmallGrid(), Model(0.3));
  grid.InsertProfile(OneBin(BinStatus::kObstacle, 0.5f), kRobot);
  // Free up to 0.3 m (x = 0.55, cells 2..5), nothing occupied, nothing beyond.
  for (int x = 2; x <= 5; ++x) EXPECT_LT(grid.Probability({x, 5}), 0.5) << x;
  for (int x = 6; x <= 9; ++x) EXPECT_FALSE(grid.IsKnown({x, 5})) << x;
}

TEST(OccupancyGridTest, FreeBearingMarksOnlyMisses) {
  OccupancyGrid grid(SmallGrid(), Model(0.6));
  grid.InsertProfile(OneBin(BinStatus::kFree, 0.36f), kRobot);
  for (int x = 2; x <= 6; ++x) EXPECT_LT(grid.Probability({x, 5}), 0.5) << x;
  EXPECT_FALSE(grid.IsKnown({7, 5}));
}

TEST(OccupancyGridTest, UnobservedBinChangesNothing) {
  OccupancyGrid grid(SmallGrid(), Model());
  EXPECT_EQ(grid.InsertProfile(OneBin(BinStatus::kUnobserved, 0.3f), kRobot), 0);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 10; ++x) EXPECT_FALSE(grid.IsKnown({x, y}));
}

TEST(OccupancyGridTest, BlindAreaIsHalfwayBetweenUnknownAndOccupiedWithoutOverridingEvidence) {
  OccupancyGrid grid(SmallGrid(), Model());
  grid.InsertProfile(OneBin(BinStatus::kFree, 0.1f), {0.25, 0.55, 0.0});  // cells 2, 3 free
  grid.InsertProfile(OneBin(BinStatus::kBlind, 0.3f, 0.3f), kRobot);       // cells 2..5 blind
  EXPECT_LT(grid.Probability({2, 5}), 0.5);
  EXPECT_LT(grid.Probability({3, 5}), 0.5);
  EXPECT_NEAR(grid.Probability({4, 5}), 0.75, 1e-3);
  EXPECT_NEAR(grid.Probability({5, 5}), 0.75, 1e-3);
  EXPECT_FALSE(grid.IsKnown({6, 5}));
}

TEST(OccupancyGridTest, ClampsAfterManyUpdatesSoTheMapCanChangeAgain) {
  OccupancyGrid grid(SmallGrid(), Model());
  for (int i = 0; i < 200; ++i) grid.InsertProfile(OneBin(BinStatus::kObstacle, 0.38f), kRobot);
  EXPECT_NEAR(grid.Probability({6, 5}), 0.97, 1e-3);
  EXPECT_NEAR(grid.Probability({3, 5}), 0.12, 1e-3);
  // The obstacle goes away: the cell becomes free after a handful of misses, not hundreds.
  int misses = 0;
  while (grid.Probability({6, 5}) >= 0.5 && misses < 100) {
    grid.InsertProfile(OneBin(BinStatus::kFree, 0.55f), kRobot);
    ++misses;
  }
  const double steps = (LogOddsFromProbability(0.97)) / -LogOddsFromProbability(0.4);
  EXPECT_EQ(misses, static_cast<int>(std::ceil(steps)));
}

TEST(OccupancyGridTest, OverlappingRaysUpdateACellOncePerProfile) {
  OccupancyGrid grid(SmallGrid(), Model());
  RadialObstacleProfile p = OneBin(BinStatus::kFree, 0.3f);
  p.bins.push_back(p.bins[0]);  // a second, almost identical bearing
  p.bins.push_back(p.bins[0]);
  grid.InsertProfile(p, kRobot);
  EXPECT_NEAR(grid.LogOdds({3, 5}), LogOddsFromProbability(0.4), 1e-3);
}

TEST(OccupancyGridTest, RaysLeavingTheGridAreClipped) {
  OccupancyGrid grid(SmallGrid(), Model(5.0));
  EXPECT_NO_THROW(grid.InsertProfile(OneBin(BinStatus::kObstacle, 3.0f), kRobot));
  EXPECT_LT(grid.Probability({9, 5}), 0.5);
}

TEST(OccupancyGridTest, TheFloorUnderTheRobotStaysFreeWhateverWasSeenThere) {
  // A wall at x = 0.63 (cell 6), seen many times from (0.25, 0.55); then the robot stands on it.
  for (double radius : {0.0, 0.12}) {
    SensorModelConfig model = Model();
    model.footprint_radius_m = radius;
    OccupancyGrid grid(SmallGrid(), model);
    for (int i = 0; i < 10; ++i) grid.InsertProfile(OneBin(BinStatus::kObstacle, 0.38f), kRobot);
    ASSERT_GT(grid.Probability({6, 5}), 0.9);
    grid.InsertProfile(OneBin(BinStatus::kUnobserved, 0.0f), {0.65, 0.55, 0.0});
    // Seen again afterwards: the footprint still wins, and only where the robot's body was.
    for (int i = 0; i < 10; ++i) grid.InsertProfile(OneBin(BinStatus::kObstacle, 0.38f), kRobot);
    if (radius == 0.0) {
      EXPECT_GT(grid.Probability({6, 5}), 0.9);
      continue;
    }
    // Cell centres within 0.12 m of (0.65, 0.55): (6, 5) and its four neighbours, not diagonals.
    for (CellIndex c : {CellIndex{6, 5}, CellIndex{5, 5}, CellIndex{7, 5}, CellIndex{6, 4}, CellIndex{6, 6}}) {
      EXPECT_DOUBLE_EQ(grid.Probability(c), model.min_probability) << c.x << "," << c.y;
      EXPECT_EQ(grid.ToRosCells()[c.y * 10 + c.x], 12) << c.x << "," << c.y;
    }
    EXPECT_FALSE(grid.UnderFootprint({7, 6}));
    EXPECT_FALSE(grid.IsKnown({7, 6}));
    EXPECT_GT(grid.LogOdds({6, 5}), 2.0);  // the evidence is kept, only overruled
    grid.Clear();
    EXPECT_FALSE(grid.UnderFootprint({6, 5}));
  }
  SensorModelConfig bad = Model();
  bad.footprint_radius_m = -0.1;
  try {
    OccupancyGrid grid(SmallGrid(), bad);
    FAIL() << "a negative footprint radius was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("footprint_radius_m"), std::string::npos) << e.what();
  }
}

TEST(OccupancyGridTest, RejectsNonFinitePoseAndBadRanges) {
  OccupancyGrid grid(SmallGrid(), Model());
  EXPECT_THROW(grid.InsertProfile(OneBin(BinStatus::kFree, 0.3f), {NAN, 0, 0}), std::invalid_argument);
  EXPECT_THROW(grid.InsertProfile(OneBin(BinStatus::kFree, INFINITY), kRobot), std::invalid_argument);
  EXPECT_THROW(OccupancyGrid(GridConfig{0.0, 10, 10, 0, 0}, Model()), ConfigError);
}

TEST(OccupancyGridTest, RosCellsAndMapServerExportUseTheStandardShades) {
  OccupancyGrid grid(SmallGrid(), Model());
  for (int i = 0; i < 5; ++i) grid.InsertProfile(OneBin(BinStatus::kObstacle, 0.38f), kRobot);
  const std::vector<int8_t> ros = grid.ToRosCells();
  EXPECT_EQ(ros[5 * 10 + 0], -1);
  EXPECT_LT(ros[5 * 10 + 3], 20);
  EXPECT_GT(ros[5 * 10 + 6], 65);
  const cv::Mat image = RenderMapImage(grid);
  // Row 0 of the image is the top of the map (y = 9), so grid row 5 is image row 4.
  EXPECT_EQ(image.at<uchar>(4, 0), 205);
  EXPECT_EQ(image.at<uchar>(4, 3), 254);
  EXPECT_EQ(image.at<uchar>(4, 6), 0);
  const auto dir = std::filesystem::temp_directory_path() / ("occupancy_grid_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  WriteRosMap(grid, dir / "map");
  std::ifstream yaml(dir / "map.yaml");
  std::string text((std::istreambuf_iterator<char>(yaml)), {});
  EXPECT_NE(text.find("image: map.pgm"), std::string::npos);
  EXPECT_NE(text.find("resolution: 0.1"), std::string::npos);
  const cv::Mat pgm = cv::imread((dir / "map.pgm").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(pgm.empty());
  EXPECT_EQ(cv::countNonZero(pgm != image), 0);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rslam::occupancy
