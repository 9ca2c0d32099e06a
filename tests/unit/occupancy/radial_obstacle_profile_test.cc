#include "services/occupancy/radial_obstacle_profile.h"

#include <gtest/gtest.h>

#include "services/occupancy/floor_segmenter.h"
#include "tests/unit/occupancy/synthetic_scene.h"

namespace rslam::occupancy {
namespace {

using testing::Render;
using testing::TrueRange;
using testing::Wall;

TEST(RadialObstacleProfileTest, RangesMatchTheRenderedWall) {
  const CameraConfig cam;
  const InversePerspectiveMap ipm(cam);
  const RopExtractor extractor({}, ipm);
  const std::vector<Wall> walls{Wall{{0.35, -1.0}, {0.35, 1.0}}};
  const auto view = Render(cam, {}, walls);
  const RadialObstacleProfile rop = extractor.Extract(FloorSegmenter({}, testing::kFloorColour).Segment(view.image));
  ASSERT_GE(rop.bins.size(), 60u);
  int obstacles = 0;
  for (size_t i = 0; i < rop.bins.size(); ++i) {
    const double truth = TrueRange({0, 0}, rop.BinCentre(i), walls);
    if (rop.bins[i].status != BinStatus::kObstacle) continue;
    ++obstacles;
    EXPECT_NEAR(rop.bins[i].range_m, truth, 0.015) << "bin " << i;
  }
  EXPECT_GE(obstacles, 50);
}

TEST(RadialObstacleProfileTest, OpenFloorIsFreeToTheScanRange) {
  const CameraConfig cam;
  const InversePerspectiveMap ipm(cam);
  const RopExtractor extractor(RopConfig{1.0, 0.5, 0.005}, ipm);
  const auto view = Render(cam, {}, {Wall{{1.5, -3}, {1.5, 3}}});
  const auto rop = extractor.Extract(FloorSegmenter({}, testing::kFloorColour).Segment(view.image));
  int free = 0;
  for (const RopBin& b : rop.bins)
    if (b.status == BinStatus::kFree) {
      ++free;
      EXPECT_LE(b.range_m, 0.5f + 1e-6f);
    } else {
      EXPECT_NE(b.status, BinStatus::kObstacle);
    }
  EXPECT_GE(free, 50);
}

TEST(RadialObstacleProfileTest, ObstacleFillingTheViewMakesEveryBearingBlind) {
  const CameraConfig cam;
  const InversePerspectiveMap ipm(cam);
  const RopExtractor extractor({}, ipm);
  const auto rop = extractor.Extract(cv::Mat::zeros(cam.height, cam.width, CV_8U));
  for (const RopBin& b : rop.bins) {
    if (b.status == BinStatus::kUnobserved) continue;
    EXPECT_EQ(b.status, BinStatus::kBlind);
    EXPECT_GT(b.nearest_visible_m, 0.05f);
  }
}

TEST(RadialObstacleProfileTest, PirouetteOfTwelveViewsCoversTheRoom) {
  const CameraConfig cam;
  const InversePerspectiveMap ipm(cam);
  const RopExtractor extractor({}, ipm);
  const FloorSegmenter segmenter({}, testing::kFloorColour);
  const std::vector<Wall> room = testing::SquareRoom(0.4);
  const Pose2D robot{0.08, -0.05, 0.3};
  PirouetteProfileBuilder pirouette(1.0);
  for (int k = 0; k < 12; ++k) {
    const double heading = k * M_PI / 6;
    const auto view = Render(cam, {robot.x, robot.y, robot.theta + heading}, room, 3.0, k + 1);
    pirouette.AddView(extractor.Extract(segmenter.Segment(view.image)), heading);
  }
  const RadialObstacleProfile full = pirouette.Build();
  ASSERT_EQ(full.bins.size(), 360u);
  int checked = 0;
  for (size_t i = 0; i < full.bins.size(); ++i) {
    const double truth = TrueRange({robot.x, robot.y}, robot.theta + full.BinCentre(i), room);
    if (truth > 0.55) continue;  // corners beyond the scan range
    ASSERT_EQ(full.bins[i].status, BinStatus::kObstacle) << "bin " << i;
    EXPECT_NEAR(full.bins[i].range_m, truth, 0.02) << "bin " << i;
    ++checked;
  }
  EXPECT_GT(checked, 300);
}

TEST(RadialObstacleProfileTest, RejectsMasksOfTheWrongShape) {
  const InversePerspectiveMap ipm{CameraConfig{}};
  const RopExtractor extractor({}, ipm);
  EXPECT_THROW(extractor.Extract(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(extractor.Extract(cv::Mat::zeros(10, 10, CV_8U)), std::invalid_argument);
  PirouetteProfileBuilder pirouette;
  EXPECT_THROW(pirouette.AddView({}, NAN), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::occupancy
