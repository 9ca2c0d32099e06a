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

TEST(ConfigurationSpaceTest, MarginGoalsOnlyWhereTheRobotFitsAtTheirCentre) {
  // 3 m x 2 m of 5 cm cells, free left of a wall at x = 30, unknown right of it. The wall has a
  // hole 10 cm wide (y 8..9) and a door 80 cm wide (y 20..35), both unseen.
  std::vector<int8_t> cells(60 * 40, 0);
  for (int y = 0; y < 40; ++y)
    for (int x = 30; x < 60; ++x) {
      const bool opening = (y >= 8 && y <= 9) || (y >= 20 && y <= 35);
      cells[y * 60 + x] = x == 30 && !opening ? 100 : -1;
    }
  GridView view{60, 40, 0.05, 0.0, 0.0, cells};
  ExplorerConfig config;
  config.robot_radius_m = 0.2;
  config.coarse_cell_factor = 4;  // 20 cm cells; x 7 holds the wall, x 8 lies past it
  const CoarseGrid cs = BuildConfigurationSpace(view, config);
  const auto margin_goal = [&](int x, int y) { return cs.margin_goal[static_cast<size_t>(y) * cs.width + x] != 0; };
  // In the door, 0.33 m from both of its sides: the robot's disc fits with 5 cm to spare.
  EXPECT_TRUE(margin_goal(7, 6));
  EXPECT_TRUE(margin_goal(7, 7));
  // At the door's sides (0.13 m from the wall's end), and past the hole: margin holding unseen
  // cells and no obstacle, but the robot does not fit there.
  EXPECT_FALSE(margin_goal(7, 5));
  EXPECT_FALSE(margin_goal(7, 8));
  EXPECT_EQ(cs.At(8, 2), CellClass::kOccupied);
  EXPECT_FALSE(cs.obstacle[2 * cs.width + 8]);
  EXPECT_TRUE(cs.unseen[2 * cs.width + 8]);
  EXPECT_FALSE(margin_goal(8, 2));
  // With no room to spare, the door's middle is still a goal; with 15 cm it is not.
  config.margin_goal_spare_m = 0.0;
  EXPECT_TRUE(BuildConfigurationSpace(view, config).margin_goal[6 * cs.width + 7]);
  config.margin_goal_spare_m = 0.15;
  EXPECT_FALSE(BuildConfigurationSpace(view, config).margin_goal[6 * cs.width + 7]);
}

TEST(ConfigurationSpaceTest, RejectsAnInconsistentView) {
  std::vector<int8_t> cells(10, 0);
  EXPECT_THROW(BuildConfigurationSpace(GridView{4, 4, 0.1, 0, 0, cells}, ExplorerConfig{}), std::invalid_argument);
  EXPECT_THROW(BuildConfigurationSpace(GridView{10, 1, NAN, 0, 0, cells}, ExplorerConfig{}), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::explorer
