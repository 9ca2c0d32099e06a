#include "services/explorer/configuration_space.h"

#include <gtest/gtest.h>

namespace rslam::explorer {
namespace {

TEST(ConfigurationSpaceTest, DilatesObstaclesByTheRobotRadiusOnTheCoarseGrid) {
  // 40 x 40 cells of 5 cm, all free, one occupied cell in the middle (20, 20).
  std::vector<int8_t> cells(40 * 40, 0);
  cells[20 * 40 + 20] = 100;
  GridView view{40, 40, 0.05, 0.0, 0.0, cells};
  ExplorerConfig config;
  config.robot_radius_m = 0.15;  // 3 cells, plus one for quantisation
  config.coarse_cell_factor = 2;
  const CoarseGrid cs = BuildConfigurationSpace(view, config);
  ASSERT_EQ(cs.width, 20);
  EXPECT_DOUBLE_EQ(cs.cell_size_m, 0.1);
  EXPECT_EQ(cs.At(10, 10), CellClass::kOccupied);  // holds the obstacle
  EXPECT_EQ(cs.At(8, 10), CellClass::kOccupied);   // fine cells 16..17: within 4 cells
  EXPECT_EQ(cs.At(7, 10), CellClass::kFree);       // fine cells 14..15: 5 or more away
  EXPECT_EQ(cs.At(0, 0), CellClass::kFree);
}

TEST(ConfigurationSpaceTest, UnknownCellsMakeGoalsButObstaclesWin) {
  std::vector<int8_t> cells(8 * 8, 0);
  cells[0] = -1;            // coarse (0, 0): unknown
  cells[7 * 8 + 7] = -1;    // coarse (1, 1): unknown and
  cells[6 * 8 + 6] = 100;   // occupied
  cells[3 * 8 + 7] = 50;    // between the thresholds: unknown, coarse (1, 0)
  GridView view{8, 8, 0.1, 0.0, 0.0, cells};
  ExplorerConfig config;
  config.robot_radius_m = 0.0;
  config.coarse_cell_factor = 4;
  const CoarseGrid cs = BuildConfigurationSpace(view, config);
  EXPECT_EQ(cs.At(0, 0), CellClass::kUnknown);
  EXPECT_EQ(cs.At(1, 0), CellClass::kUnknown);
  EXPECT_EQ(cs.At(1, 1), CellClass::kOccupied);
  EXPECT_EQ(cs.At(0, 1), CellClass::kFree);
}

TEST(ConfigurationSpaceTest, UncertainCellsMakeNoGoalWhenToldNotTo) {
  std::vector<int8_t> cells(8 * 8, 0);
  cells[3 * 8 + 7] = 50;  // coarse (1, 0): uncertain only
  cells[0] = -1;          // coarse (0, 0): never seen,
  cells[1] = 50;          // and uncertain
  GridView view{8, 8, 0.1, 0.0, 0.0, cells};
  ExplorerConfig config;
  config.robot_radius_m = 0.0;
  config.coarse_cell_factor = 4;
  config.uncertain_cells_are_goals = false;
  const CoarseGrid cs = BuildConfigurationSpace(view, config);
  EXPECT_EQ(cs.At(1, 0), CellClass::kUncertain);
  EXPECT_EQ(cs.At(0, 0), CellClass::kUnknown);
  EXPECT_EQ(cs.At(0, 1), CellClass::kFree);
  EXPECT_TRUE(cs.unseen[1]);
  // Below min_unknown_cells_for_goal a block is free, whatever its unknown cells are.
  config.min_unknown_cells_for_goal = 2;
  const CoarseGrid two = BuildConfigurationSpace(view, config);
  EXPECT_EQ(two.At(1, 0), CellClass::kFree);
  EXPECT_EQ(two.At(0, 0), CellClass::kUncertain) << "a goal only if both cells counted";
  config.uncertain_cells_are_goals = true;
  EXPECT_EQ(BuildConfigurationSpace(view, config).At(0, 0), CellClass::kUnknown);
}

TEST(ConfigurationSpaceTest, RejectsAnInconsistentView) {
  std::vector<int8_t> cells(10, 0);
  EXPECT_THROW(BuildConfigurationSpace(GridView{4, 4, 0.1, 0, 0, cells}, ExplorerConfig{}), std::invalid_argument);
  EXPECT_THROW(BuildConfigurationSpace(GridView{10, 1, NAN, 0, 0, cells}, ExplorerConfig{}), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::explorer
