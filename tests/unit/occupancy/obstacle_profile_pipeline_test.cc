#include "services/occupancy/obstacle_profile_pipeline.h"

#include <gtest/gtest.h>

#include "services/occupancy/occupancy_grid.h"
#include "tests/unit/occupancy/synthetic_scene.h"

namespace rslam::occupancy {
namespace {

ObstacleProfileConfig Config() {
  ObstacleProfileConfig config;
  config.floor_colour_bgr = {testing::kFloorColour[0], testing::kFloorColour[1], testing::kFloorColour[2]};
  return config;
}

TEST(ObstacleProfilePipelineTest, PirouetteInARoomMapsItsWallsIntoTheGrid) {
  const ObstacleProfilePipeline pipeline(Config());
  const std::vector<testing::Wall> room = testing::SquareRoom(0.3);
  const Pose2D robot{0.05, 0.02, 0.0};
  PirouetteProfileBuilder pirouette;
  for (int k = 0; k < 12; ++k) {
    const double heading = k * M_PI / 6;
    const auto view = testing::Render(Config().camera, {robot.x, robot.y, heading}, room, 3.0, k + 7);
    pirouette.AddView(pipeline.ProfileFromImage(view.image), heading);
  }
  OccupancyGrid grid(GridConfig{0.01, 100, 100, -0.5, -0.5}, SensorModelConfig{});
  grid.InsertProfile(pirouette.Build(), robot);
  // Each wall is occupied within a cell (1 cm) of where it stands; the floor between is free.
  auto wall_seen_near = [&](double x, double y) {
    double best = 0.0;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const CellIndex c = grid.CellOf(x, y);
        best = std::max(best, grid.Probability({c.x + dx, c.y + dy}));
      }
    return best;
  };
  EXPECT_GT(wall_seen_near(0.305, 0.02), 0.6);   // east wall
  EXPECT_GT(wall_seen_near(0.05, 0.305), 0.6);   // north wall
  EXPECT_GT(wall_seen_near(-0.305, 0.02), 0.6);  // west wall, 35 cm away
  EXPECT_GT(wall_seen_near(0.05, -0.305), 0.6);  // south wall
  EXPECT_LT(grid.Probability(grid.CellOf(0.2, 0.0)), 0.5);
  EXPECT_LT(grid.Probability(grid.CellOf(-0.2, -0.1)), 0.5);
  EXPECT_FALSE(grid.IsKnown(grid.CellOf(0.45, 0.45)));  // outside the room
}

TEST(ObstacleProfilePipelineTest, RejectsImagesOfTheWrongSizeAndBadConfig) {
  const ObstacleProfilePipeline pipeline(Config());
  EXPECT_THROW(pipeline.ProfileFromImage(cv::Mat(100, 100, CV_8UC3)), std::invalid_argument);
  ObstacleProfileConfig bad = Config();
  bad.floor_colour_bgr = {1, 2};
  EXPECT_THROW(ObstacleProfilePipeline{bad}, ConfigError);
}

}  // namespace
}  // namespace rslam::occupancy
