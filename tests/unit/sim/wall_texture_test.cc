#include "tools/sim/wall_texture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <set>

#include "tests/unit/sim/test_worlds.h"
#include "tools/sim/deterministic_random.h"

namespace rslam::sim {
namespace {

RayHit HitTowards(const WorldMap& world, const Eigen::Vector2d& from, const Eigen::Vector2d& target) {
  const Eigen::Vector2d d = target - from;
  return world.CastRay(from, std::atan2(d.y(), d.x()));
}

TEST(WallTextureTest, SameWallPointLooksTheSameFromAnyViewpoint) {
  const WorldMap world = testing::BoxRoom(200, 100);  // 8 m x 4 m
  SceneConfig scene;
  const WallTexture texture(scene);
  // Points off texel boundaries (texels are 0.6 m / 32 = 18.75 mm wide).
  for (double along = 0.304; along < 7.7; along += 0.37) {
    const Eigen::Vector2d wall_point(along, 3.96);  // on the north wall's face
    const RayHit a = HitTowards(world, Eigen::Vector2d(1.0, 1.0), wall_point);
    const RayHit b = HitTowards(world, Eigen::Vector2d(6.5, 2.0), wall_point);
    ASSERT_NEAR((a.point - wall_point).norm(), 0.0, 1e-9);
    ASSERT_NEAR((b.point - wall_point).norm(), 0.0, 1e-9);
    for (double z : {0.1, 0.9, 1.7}) EXPECT_EQ(texture.Sample(a, z), texture.Sample(b, z)) << along;
  }
}

TEST(WallTextureTest, WallsAreVariedAndNeverNearTheFloorColour) {
  const WorldMap world = testing::BoxRoom(200, 100);
  SceneConfig scene;
  const WallTexture texture(scene);
  DeterministicRandom random(3);
  std::set<int> colours;
  int min_floor_distance = 1000;
  for (int i = 0; i < 5000; ++i) {
    const RayHit hit = world.CastRay(Eigen::Vector2d(4.0, 2.0), random.Uniform() * 2 * M_PI);
    const cv::Vec3b c = texture.Sample(hit, random.Uniform() * scene.wall_height_m);
    colours.insert(c[0] << 16 | c[1] << 8 | c[2]);
    min_floor_distance = std::min(min_floor_distance, std::abs(c[0] - scene.floor_bgr[0]) +
                                                          std::abs(c[1] - scene.floor_bgr[1]) +
                                                          std::abs(c[2] - scene.floor_bgr[2]));
  }
  EXPECT_GT(colours.size(), 500u);
  EXPECT_GE(min_floor_distance, 60);  // 20 levels in every channel
}

TEST(WallTextureTest, SeedChangesThePatterns) {
  const WorldMap world = testing::BoxRoom(200, 100);
  SceneConfig scene;
  const WallTexture a(scene);
  scene.texture_seed += 1;
  const WallTexture b(scene);
  int differ = 0;
  for (int i = 0; i < 100; ++i) {
    const RayHit hit = world.CastRay(Eigen::Vector2d(4.0, 2.0), i * 0.0628);
    differ += a.Sample(hit, 1.0) != b.Sample(hit, 1.0);
  }
  EXPECT_GT(differ, 50);
}

}  // namespace
}  // namespace rslam::sim
