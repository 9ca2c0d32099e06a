#include "services/occupancy/inverse_perspective_map.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rslam::occupancy {
namespace {

// A paper-like camera: 320 x 240, 60 degrees horizontal field of view (fx = 277 px), 10 cm above
// the floor, tilted 32 degrees down, so the floor is visible from about 7 cm to about 66 cm ahead.
CameraConfig PaperLikeCamera() { return CameraConfig{}; }

TEST(InversePerspectiveMapTest, PaperLikeCameraSeesFloorFromNearToBeyondFortyCentimetres) {
  const InversePerspectiveMap ipm(PaperLikeCamera());
  const auto bottom = ipm.FloorPoint(160, 239);
  const auto top = ipm.FloorPoint(160, 0);
  ASSERT_TRUE(bottom && top);
  EXPECT_LT(bottom->x, 0.08);
  EXPECT_GT(top->x, 0.40);
}

TEST(InversePerspectiveMapTest, LookupTableAgreesWithAnalyticProjectionWithinHalfACentimetre) {
  // The paper's check (section 3.1): quantising a floor point to its pixel and reading the table
  // back must cost less than 0.5 cm up to about 40 cm.
  const InversePerspectiveMap ipm(PaperLikeCamera());
  int checked = 0;
  double worst = 0.0;
  for (double x = 0.08; x <= 0.40; x += 0.01) {
    for (double y = -0.2; y <= 0.2; y += 0.01) {
      if (std::hypot(x, y) > 0.40) continue;
      const auto pixel = ipm.ProjectFloorToPixel(x, y);
      ASSERT_TRUE(pixel);
      const int u = static_cast<int>(std::lround(pixel->x)), v = static_cast<int>(std::lround(pixel->y));
      const auto back = ipm.FloorPoint(u, v);
      if (!back) continue;  // outside the image
      worst = std::max(worst, std::hypot(back->x - x, back->y - y));
      ++checked;
    }
  }
  EXPECT_GT(checked, 300);
  EXPECT_LT(worst, 0.005);
}

TEST(InversePerspectiveMapTest, ForwardAndInverseProjectionsAreInverse) {
  const InversePerspectiveMap ipm(PaperLikeCamera());
  for (double u : {0.0, 100.5, 319.0})
    for (double v : {60.0, 150.0, 239.0}) {
      const auto floor = ipm.ProjectPixelToFloor(u, v);
      ASSERT_TRUE(floor);
      const auto pixel = ipm.ProjectFloorToPixel(floor->x, floor->y);
      ASSERT_TRUE(pixel);
      EXPECT_NEAR(pixel->x, u, 1e-6);
      EXPECT_NEAR(pixel->y, v, 1e-6);
    }
}

TEST(InversePerspectiveMapTest, PixelsAboveTheHorizonHaveNoFloorPoint) {
  CameraConfig camera = PaperLikeCamera();
  camera.tilt_rad = 0.2;  // horizon at v = cy - fy tan(tilt), about row 63
  const InversePerspectiveMap ipm(camera);
  EXPECT_FALSE(ipm.FloorPoint(160, 30));
  EXPECT_TRUE(ipm.FloorPoint(160, 100));
  EXPECT_FALSE(ipm.FloorPoint(-1, 100));
  EXPECT_FALSE(ipm.FloorPoint(160, 240));
}

TEST(InversePerspectiveMapTest, LeftOfTheImageIsLeftOfTheRobot) {
  const InversePerspectiveMap ipm(PaperLikeCamera());
  EXPECT_GT(ipm.FloorPoint(10, 200)->y, 0.0);
  EXPECT_LT(ipm.FloorPoint(310, 200)->y, 0.0);
}

}  // namespace
}  // namespace rslam::occupancy
