// The walls' direction modulo 90 degrees (services/odometry/wall_direction.h): of exact geometry,
// and of frames the simulator renders in the shipped uwb-room world against the true heading.

#include "services/odometry/wall_direction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/config/config_loader.h"
#include "services/occupancy/obstacle_profile_pipeline.h"
#include "services/odometry/odometry_node_config.h"
#include "tools/sim/camera_renderer.h"
#include "tools/sim/world_map.h"

namespace rslam::odometry {
namespace {

// One point per degree over a 60-degree view of the straight wall through (distance, 0) (robot
// frame) running at `angle` to the robot's sideways axis (0: the wall faces the robot).
std::vector<Eigen::Vector2d> WallAhead(double distance, double angle) {
  std::vector<Eigen::Vector2d> out;
  const Eigen::Vector2d along(-std::sin(angle), std::cos(angle)), base(distance, 0.0);
  for (int i = -30; i < 30; ++i) {
    const double b = (i + 0.5) * M_PI / 180.0;
    const Eigen::Vector2d ray(std::cos(b), std::sin(b));
    // base + s * along = t * ray
    const double det = ray.x() * along.y() - ray.y() * along.x();
    if (std::abs(det) < 1e-9) continue;
    const double t = (base.x() * along.y() - base.y() * along.x()) / det;
    if (t > 0) out.push_back(t * ray);
  }
  return out;
}

TEST(WallDirectionTest, AWallsDirectionIsTakenModuloNinetyDegrees) {
  const WallDirectionConfig config;
  for (double angle : {0.0, 0.3, -0.5, 0.9, 1.2}) {
    const auto wall = WallDirection(WallAhead(1.0, angle), config);
    ASSERT_TRUE(wall.has_value()) << angle;
    // The wall runs along `along` = angle + 90 degrees: modulo 90 degrees, `angle`.
    EXPECT_NEAR(std::remainder(*wall - angle, M_PI / 2), 0.0, 1e-6) << angle;
    EXPECT_LE(std::abs(*wall), M_PI / 4 + 1e-9);
  }
  // Too far (beyond max_range_m), too little of it, or no straight wall: no direction.
  EXPECT_FALSE(WallDirection(WallAhead(3.0, 0.0), config).has_value());
  const std::vector<Eigen::Vector2d> wall = WallAhead(1.0, 0.0);
  EXPECT_FALSE(WallDirection(std::vector<Eigen::Vector2d>(wall.begin(), wall.begin() + 3), config).has_value());
  std::vector<Eigen::Vector2d> table;  // a round table of radius 0.4 m, 1 m ahead
  for (int i = -60; i <= 60; ++i) {
    const double a = M_PI + i * M_PI / 180.0;
    table.emplace_back(1.0 + 0.4 * std::cos(a), 0.4 * std::sin(a));
  }
  EXPECT_FALSE(WallDirection(table, config).has_value());
}

TEST(WallDirectionTest, RenderedFramesOfTheShippedWorldShowItsAxes) {
  // The camera at poses across the uwb-room map (its walls run along x and y; most poses see no
  // wall within 1.5 m): the frames that give a wall direction give the true heading's, modulo 90
  // degrees, but for a few (a corner, a table's edge: 162 frames, 140 right). With the demo's
  // boundary (read out to 3 m) and wall directions (walls out to 2.5 m): 228 frames, 190 right.
  const sim::WorldMap world = sim::WorldMap::LoadFromYaml(RSLAM_SOURCE_DIR "/deploy/worlds/uwb-room.yaml");
  sim::CameraRenderer renderer(world, sim::SceneConfig{}, sim::CameraConfig{});
  OdometryNodeConfig demo_odometry;
  LoadConfigSection(LoadYamlFile(RSLAM_SOURCE_DIR "/deploy/config/demo.yaml"), "odometry", demo_odometry);
  occupancy::ObstacleProfilePipeline boundary(demo_odometry.floor.boundary);
  const WallDirectionConfig near;
  const WallDirectionConfig& demo = demo_odometry.floor.wall_direction;
  int frames = 0, with_near = 0, right_near = 0, with_demo = 0, right_demo = 0;
  uint64_t seq = 0;
  const auto is_right = [](double theta, double wall) { return std::abs(std::remainder(theta + wall, M_PI / 2)) < 0.05; };
  for (double x = -6.0; x <= 6.0; x += 0.5)
    for (double y = -6.0; y <= 6.0; y += 0.5)
      for (double theta = 0.1; theta < 2 * M_PI; theta += 0.7) {
        if (!world.IsDiscFree({x, y}, 0.2)) continue;
        ++frames;
        const occupancy::RadialObstacleProfile profile = boundary.ProfileFromImage(renderer.Render({x, y, theta}, seq++));
        std::vector<Eigen::Vector2d> points;
        profile.ObstaclePoints(points);
        if (const auto wall = WallDirection(points, near)) {
          ++with_near;
          right_near += is_right(theta, *wall);
        }
        if (const auto wall = WallDirection(points, demo)) {
          ++with_demo;
          right_demo += is_right(theta, *wall);
        }
      }
  RecordProperty("frames", frames);
  RecordProperty("with_direction", with_near);
  RecordProperty("with_direction_demo", with_demo);
  std::printf("uwb-room: %d frames; within %.1f m %d with a wall direction, %d of them within 0.05 rad of the axes; "
              "within %.1f m %d, %d right\n",
              frames, near.max_range_m, with_near, right_near, demo.max_range_m, with_demo, right_demo);
  EXPECT_GT(frames, 1000);
  EXPECT_GT(with_near, frames / 25);
  EXPECT_GT(right_near, 0.8 * with_near);
  EXPECT_GT(with_demo, with_near + with_near / 5);  // farther walls: more frames hold the heading
  EXPECT_GT(right_demo, 0.8 * with_demo);
}

}  // namespace
}  // namespace rslam::odometry
