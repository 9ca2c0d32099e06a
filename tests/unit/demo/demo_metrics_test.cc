// The demo's figures of merit (tools/demo/demo_metrics.h): placing a map in the world.

#include "tools/demo/demo_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

namespace rslam::demo {
namespace {

msg::Experience At(uint32_t id, double x, double y) {
  msg::Experience e{};
  e.id = id;
  e.x_m = x;
  e.y_m = y;
  return e;
}

TEST(DemoMetricsTest, FitMapToWorldRecoversATurnedAndShiftedMap) {
  // World positions of four experiences; the map holds them turned by 0.4 rad and shifted.
  const std::map<uint32_t, sim::Pose2D> truth = {
      {0, {1.0, 2.0, 0.0}}, {1, {3.0, 2.5, 0.0}}, {2, {2.0, -1.0, 0.0}}, {5, {-1.0, 0.5, 0.0}}};
  const sim::Pose2D map_to_world{0.7, -0.3, 0.4};
  std::vector<msg::Experience> map;
  const double c = std::cos(-map_to_world.theta), s = std::sin(-map_to_world.theta);
  for (const auto& [id, w] : truth) {
    const double dx = w.x - map_to_world.x, dy = w.y - map_to_world.y;
    map.push_back(At(id, c * dx - s * dy, s * dx + c * dy));
  }
  map.push_back(At(9, 50.0, 50.0));  // no ground truth: ignored
  const auto fit = FitMapToWorld(map, truth);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->x, map_to_world.x, 1e-9);
  EXPECT_NEAR(fit->y, map_to_world.y, 1e-9);
  EXPECT_NEAR(fit->theta, map_to_world.theta, 1e-9);
  for (const auto& e : map) {
    if (!truth.count(e.id)) continue;
    const sim::Pose2D w = MapToWorld(*fit, e.x_m, e.y_m);
    EXPECT_NEAR(w.x, truth.at(e.id).x, 1e-9);
    EXPECT_NEAR(w.y, truth.at(e.id).y, 1e-9);
  }
}

TEST(DemoMetricsTest, FitMapToWorldIsTheLeastSquaresTurnOfANoisyMap) {
  // Symmetric errors around the true positions leave the fit at the identity.
  const std::map<uint32_t, sim::Pose2D> truth = {{0, {0, 0, 0}}, {1, {2, 0, 0}}, {2, {2, 2, 0}}, {3, {0, 2, 0}}};
  const std::vector<msg::Experience> map = {At(0, 0.1, 0), At(1, 1.9, 0), At(2, 2.1, 2), At(3, -0.1, 2)};
  const auto fit = FitMapToWorld(map, truth);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->theta, 0.0, 1e-9);
  EXPECT_NEAR(fit->x, 0.0, 1e-9);
  EXPECT_NEAR(fit->y, 0.0, 1e-9);
}

TEST(DemoMetricsTest, FitMapToWorldNeedsTwoExperiencesWithGroundTruth) {
  const std::map<uint32_t, sim::Pose2D> truth = {{0, {1.0, 2.0, 0.0}}};
  const std::vector<msg::Experience> map = {At(0, 0, 0), At(1, 1, 0)};
  EXPECT_FALSE(FitMapToWorld(map, truth).has_value());
}

}  // namespace
}  // namespace rslam::demo
