#include "tools/sim/camera_renderer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tests/unit/sim/test_worlds.h"

namespace rslam::sim {
namespace {

using testing::BoxRoom;
using testing::UwbRoom;

bool IsColour(const cv::Vec3b& px, const std::vector<int>& bgr) {
  return px[0] == bgr[0] && px[1] == bgr[1] && px[2] == bgr[2];
}

// Inverse perspective mapping written independently of the renderer: the floor point seen
// through image position (u_px, v_px) (pixel-edge coordinates) of a camera at height h tilted
// down by t. Returns the horizontal distance and sets the azimuth (left positive).
double FloorDistance(const CameraConfig& cam, double f, double u_px, double v_px, double* azimuth) {
  const double x = (u_px - cam.width / 2.0) / f;
  const double y = (v_px - cam.height / 2.0) / f;
  const double t = cam.tilt_rad;
  const double forward = std::cos(t) - y * std::sin(t);
  const double left = -x;
  const double down = std::sin(t) + y * std::cos(t);
  *azimuth = std::atan2(left, forward);
  return cam.height_m / down * std::hypot(forward, left);
}

struct BoundaryCheck {
  int columns = 0;
  int within_3_percent = 0;
  double worst = 0.0;
};

// For each column: the first non-floor row from the bottom, mapped back through the floor
// boundary (the pixel edge below it), against the true wall distance along that azimuth.
BoundaryCheck CheckFloorBoundary(const WorldMap& world, const CameraConfig& cam, const Pose2D& pose,
                                 double max_distance) {
  SceneConfig scene;
  CameraRenderer renderer(world, scene, cam);
  const cv::Mat image = renderer.Render(pose);
  BoundaryCheck check;
  for (int u = 0; u < cam.width; ++u) {
    int v = cam.height - 1;
    while (v >= 0 && IsColour(image.at<cv::Vec3b>(v, u), scene.floor_bgr)) --v;
    if (v < 0 || v == cam.height - 1) continue;  // no floor or no wall in this column
    double azimuth = 0;
    const double seen = FloorDistance(cam, renderer.focal_length_px(), u + 0.5, v + 1.0, &azimuth);
    const Eigen::Vector2d camera_position(pose.x + cam.forward_offset_m * std::cos(pose.theta),
                                          pose.y + cam.forward_offset_m * std::sin(pose.theta));
    const double truth = world.CastRay(camera_position, pose.theta + azimuth).distance;
    if (truth > max_distance) continue;
    const double error = std::abs(seen - truth) / truth;
    ++check.columns;
    if (error < 0.03) ++check.within_3_percent;
    check.worst = std::max(check.worst, error);
  }
  return check;
}

TEST(CameraRendererTest, FloorBoundaryMapsBackToTheWallDistanceInABoxRoom) {
  const WorldMap world = BoxRoom(100, 80);  // 4 m x 3.2 m
  CameraConfig cam;
  cam.noise_amplitude = 0;
  for (double theta : {0.0, 0.4, 1.3, -2.2, 3.0}) {
    const BoundaryCheck check = CheckFloorBoundary(world, cam, Pose2D{1.6, 1.5, theta}, 10.0);
    EXPECT_EQ(check.columns, cam.width) << "theta " << theta;
    // Corners, where the distance jumps between neighbouring azimuths, may miss by a ray.
    EXPECT_GE(check.within_3_percent, check.columns - 6) << "theta " << theta << " worst " << check.worst;
  }
  cam.forward_offset_m = 0.5;  // the camera ahead of the robot's centre sees the wall 0.5 m closer
  const BoundaryCheck offset = CheckFloorBoundary(world, cam, Pose2D{1.6, 1.5, 0.0}, 10.0);
  EXPECT_EQ(offset.columns, cam.width);
  EXPECT_GE(offset.within_3_percent, offset.columns - 6) << "worst " << offset.worst;
  cam.forward_offset_m = 0.0;
  cam.tilt_rad = 0.0;  // level camera: the horizon row splits the image
  const BoundaryCheck level = CheckFloorBoundary(world, cam, Pose2D{1.6, 1.5, 2.0}, 10.0);
  EXPECT_EQ(level.columns, cam.width);
  EXPECT_GE(level.within_3_percent, level.columns - 6) << "worst " << level.worst;
}

TEST(CameraRendererTest, FloorBoundaryMapsBackToTheWallDistanceInTheUwbRoom) {
  const WorldMap& world = UwbRoom();
  const Pose2D start = world.DefaultStartPose();
  CameraConfig cam;
  cam.width = 640;
  cam.height = 480;
  cam.tilt_rad = 0.4;
  int columns = 0, good = 0;
  for (int k = 0; k < 8; ++k) {
    const BoundaryCheck check = CheckFloorBoundary(world, cam, Pose2D{start.x, start.y, k * M_PI / 4}, 3.5);
    columns += check.columns;
    good += check.within_3_percent;
  }
  ASSERT_GT(columns, 500);
  EXPECT_GE(good, columns * 95 / 100);
}

TEST(CameraRendererTest, SamePoseRendersTheSameImage) {
  const WorldMap& world = UwbRoom();
  const Pose2D start = world.DefaultStartPose();
  SceneConfig scene;
  CameraConfig cam;
  CameraRenderer a(world, scene, cam), b(world, scene, cam);
  const cv::Mat first = a.Render(start, 5);
  a.Render(Pose2D{start.x + 1, start.y, 1.0}, 6);
  EXPECT_EQ(cv::norm(first, a.Render(start, 5), cv::NORM_L1), 0.0);
  EXPECT_EQ(cv::norm(first, b.Render(start, 5), cv::NORM_L1), 0.0);
  EXPECT_EQ(first.type(), CV_8UC3);
  EXPECT_EQ(first.cols, cam.width);
  EXPECT_EQ(first.rows, cam.height);
}

double MeanAbsDiff(const cv::Mat& a, const cv::Mat& b) { return cv::norm(a, b, cv::NORM_L1) / a.total() / 3.0; }

TEST(CameraRendererTest, DifferentPlacesRenderDifferentImages) {
  const WorldMap& world = UwbRoom();
  const Pose2D start = world.DefaultStartPose();
  SceneConfig scene;
  CameraConfig cam;
  cam.tilt_rad = 0.1;  // look at the walls rather than the floor
  CameraRenderer renderer(world, scene, cam);
  const std::vector<Pose2D> places = {
      start, {start.x, start.y, M_PI / 2}, {start.x, start.y, M_PI}, {start.x, start.y, -M_PI / 2},
      {start.x - 1.5, start.y + 0.5, 0.3}};
  std::vector<cv::Mat> images;
  for (const Pose2D& p : places) images.push_back(renderer.Render(p));
  for (size_t i = 0; i < images.size(); ++i) {
    for (size_t j = i + 1; j < images.size(); ++j) {
      EXPECT_GT(MeanAbsDiff(images[i], images[j]), 15.0) << "places " << i << " and " << j;
    }
  }
}

// A pixel is exactly the floor colour if and only if its ray meets the floor before any wall
// (checked against an independent ray cast), so a floor segmenter seeded on the colour is exact.
TEST(CameraRendererTest, FloorIsExactlyUniformAndExactlyWhereTheGeometrySaysFloor) {
  const WorldMap& world = UwbRoom();
  const Pose2D start = world.DefaultStartPose();
  SceneConfig scene;
  CameraConfig cam;
  cam.noise_amplitude = 8;  // noise on walls must not leak onto the floor by default
  CameraRenderer renderer(world, scene, cam);
  for (int k = 0; k < 3; ++k) {
    const Pose2D pose{start.x - 0.5 * k, start.y + 0.3 * k, k * 2.1};
    const cv::Mat image = renderer.Render(pose, k);
    int floor_pixels = 0, mismatches = 0;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        double azimuth = 0, rise = 0;
        ASSERT_TRUE(renderer.PixelRay(u, v, &azimuth, &rise));
        const double wall = world.CastRay(Eigen::Vector2d(pose.x, pose.y), pose.theta + azimuth).distance;
        const double z = cam.height_m + rise * wall;  // height where the ray reaches the wall
        if (std::abs(z) < 1e-4) continue;              // grazing the wall foot: float vs double
        const bool floor = IsColour(image.at<cv::Vec3b>(v, u), scene.floor_bgr);
        floor_pixels += floor;
        mismatches += floor != (z < 0);
      }
    }
    EXPECT_EQ(mismatches, 0) << "pose " << k;
    EXPECT_GT(floor_pixels, cam.width * cam.height / 4);
  }
}

TEST(CameraRendererTest, NoiseChangesWithTheFrameIndexButNotTheFloor) {
  const WorldMap& world = UwbRoom();
  const Pose2D start = world.DefaultStartPose();
  SceneConfig scene;
  CameraConfig noisy;
  noisy.noise_amplitude = 4;
  CameraConfig clean = noisy;
  clean.noise_amplitude = 0;
  CameraRenderer a(world, scene, noisy), c(world, scene, clean);
  const cv::Mat f1 = a.Render(start, 1), f2 = a.Render(start, 2), exact = c.Render(start, 1);
  EXPECT_GT(MeanAbsDiff(f1, f2), 0.3);
  EXPECT_LT(MeanAbsDiff(f1, exact), 4.0);
  const int bottom = noisy.height - 1;
  for (int u = 0; u < noisy.width; ++u) EXPECT_TRUE(IsColour(f1.at<cv::Vec3b>(bottom, u), scene.floor_bgr));
}

TEST(CameraRendererTest, PanoramaMasksTheDeadZoneAndShiftsWithRotation) {
  const WorldMap& world = UwbRoom();
  const Pose2D start = world.DefaultStartPose();
  SceneConfig scene;
  CameraConfig cam;
  cam.panoramic = true;
  cam.width = 72;
  cam.height = 28;
  cam.tilt_rad = 0.0;
  cam.noise_amplitude = 0;
  cam.dead_zone_width_rad = M_PI / 2;  // 18 columns behind the robot
  CameraRenderer renderer(world, scene, cam);
  const cv::Mat a = renderer.Render(start);
  int masked = 0;
  for (int u = 0; u < cam.width; ++u) {
    bool black = true;
    for (int v = 0; v < cam.height; ++v) black &= a.at<cv::Vec3b>(v, u) == cv::Vec3b(0, 0, 0);
    masked += black;
    double azimuth = 0, rise = 0;
    EXPECT_EQ(renderer.PixelRay(u, 0, &azimuth, &rise), !black) << "column " << u;
  }
  EXPECT_EQ(masked, 18);
  // Turning left by k columns' worth of azimuth moves the scene k columns to the right.
  const int k = 5;
  const cv::Mat b = renderer.Render(Pose2D{start.x, start.y, start.theta + k * 2 * M_PI / cam.width});
  double diff = 0;
  int compared = 0;
  for (int u = 0; u + k < cam.width; ++u) {
    double az = 0, rise = 0;
    if (!renderer.PixelRay(u, 0, &az, &rise) || !renderer.PixelRay(u + k, 0, &az, &rise)) continue;
    diff += cv::norm(a.col(u), b.col(u + k), cv::NORM_L1);
    compared += cam.height * 3;
  }
  ASSERT_GT(compared, 0);
  EXPECT_LT(diff / compared, 1.0);
  // Sanity: the unshifted images differ.
  EXPECT_GT(MeanAbsDiff(a, b), 5.0);
}

TEST(CameraRendererTest, RefusesNonFinitePoseAndBadConfig) {
  const WorldMap& world = UwbRoom();
  SceneConfig scene;
  CameraConfig cam;
  CameraRenderer renderer(world, scene, cam);
  EXPECT_THROW(renderer.Render(Pose2D{std::nan(""), 0, 0}), std::invalid_argument);
  EXPECT_THROW(renderer.Render(Pose2D{0, 0, INFINITY}), std::invalid_argument);
  cam.width = 0;
  EXPECT_THROW(CameraRenderer(world, scene, cam), ConfigError);
}

}  // namespace
}  // namespace rslam::sim
