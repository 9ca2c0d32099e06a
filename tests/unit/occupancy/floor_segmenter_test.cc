#include "services/occupancy/floor_segmenter.h"

#include <gtest/gtest.h>

#include "tests/unit/occupancy/synthetic_scene.h"

namespace rslam::occupancy {
namespace {

using testing::Box;
using testing::IoU;
using testing::Render;
using testing::Wall;

std::vector<Wall> WallAheadWithBox() {
  std::vector<Wall> walls{Wall{{0.45, -1.0}, {0.45, 1.0}}};
  for (const Wall& w : Box(0.22, 0.04, 0.28, 0.10, 0.08, {30, 30, 200})) walls.push_back(w);
  return walls;
}
const std::vector<testing::BoxTop> kBoxTop{{0.22, 0.04, 0.28, 0.10, 0.08, {30, 30, 200}}};

TEST(FloorSegmenterTest, SegmentsRenderedFloorAgainstTexturedWallAndObstacle) {
  const CameraConfig cam;
  const auto view = Render(cam, {}, WallAheadWithBox(), 3.0, 1, kBoxTop);
  const FloorSegmenter segmenter({}, testing::kFloorColour);
  const cv::Mat mask = segmenter.Segment(view.image);
  EXPECT_GT(IoU(mask, view.true_floor), 0.95);
  EXPECT_GT(cv::countNonZero(view.true_floor), 10000);
}

TEST(FloorSegmenterTest, SearchesTheBottomRowWhenTheCentreIsAnObstacle) {
  const CameraConfig cam;
  // A low box right in front of the robot covers the bottom-centre pixel.
  std::vector<Wall> walls{Wall{{0.5, -1.0}, {0.5, 1.0}}};
  for (const Wall& w : Box(0.03, -0.025, 0.10, 0.025, 0.06, {200, 40, 40})) walls.push_back(w);
  const auto view = Render(cam, {}, walls, 3.0, 1, {testing::BoxTop{0.03, -0.025, 0.10, 0.025, 0.06, {200, 40, 40}}});
  ASSERT_EQ(view.true_floor.at<uchar>(cam.height - 1, cam.width / 2), 0);
  const FloorSegmenter segmenter({}, testing::kFloorColour);
  const cv::Mat mask = segmenter.Segment(view.image);
  EXPECT_EQ(mask.at<uchar>(cam.height - 1, cam.width / 2), 0);  // the fill did not start in the box
  EXPECT_GT(IoU(mask, view.true_floor), 0.95);
}

TEST(FloorSegmenterTest, ObstacleFillingTheViewGivesAnEmptyMask) {
  const CameraConfig cam;
  const auto view = Render(cam, {}, {Wall{{0.05, -1.0}, {0.05, 1.0}, 0.5}});
  const FloorSegmenter segmenter({}, testing::kFloorColour);
  EXPECT_EQ(cv::countNonZero(segmenter.Segment(view.image)), 0);
}

TEST(FloorSegmenterTest, LearnsTheFloorColourFromAFloorRegion) {
  const CameraConfig cam;
  const auto view = Render(cam, {}, WallAheadWithBox());
  const cv::Vec3b learned = FloorSegmenter::LearnFloorColour(view.image, cv::Rect(140, 220, 40, 20));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(learned[c], testing::kFloorColour[c], 2);
  EXPECT_THROW(FloorSegmenter::LearnFloorColour(view.image, cv::Rect(1000, 1000, 5, 5)), std::invalid_argument);
}

TEST(FloorSegmenterTest, RejectsBadImages) {
  const FloorSegmenter segmenter({}, testing::kFloorColour);
  EXPECT_THROW(segmenter.Segment(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(segmenter.Segment(cv::Mat(10, 10, CV_32FC3)), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::occupancy
