#include "services/explorer/exploration_transform.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace rslam::explorer {
namespace {

// The oracle: relax every edge until nothing changes (Bellman-Ford), same moves and costs; trav
// holds step factors (a step costs 10 or 14 times the larger factor of its two cells, a goal's at
// least 1), so 0/1 masks give the unweighted transform.
std::vector<int32_t> BruteForce(int w, int h, const std::vector<uint8_t>& trav, const std::vector<uint8_t>& goal) {
  std::vector<int64_t> d(w * h, INT64_MAX);
  for (int i = 0; i < w * h; ++i)
    if (goal[i]) d[i] = 0;
  auto open = [&](int x, int y) { return trav[y * w + x] || goal[y * w + x]; };
  auto factor = [&](int x, int y) { return std::max<int64_t>(trav[y * w + x], goal[y * w + x] ? 1 : 0); };
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (!trav[y * w + x]) continue;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            if (d[ny * w + nx] == INT64_MAX) continue;
            const bool diag = dx && dy;
            // Moving from (nx, ny) into (x, y) passes between (x, ny) and (nx, y).
            if (diag && !(open(x, ny) && open(nx, y))) continue;
            const int64_t c = d[ny * w + nx] + (diag ? 14 : 10) * std::max(factor(x, y), factor(nx, ny));
            if (c < d[y * w + x]) { d[y * w + x] = c; changed = true; }
          }
      }
  }
  std::vector<int32_t> out(w * h);
  for (int i = 0; i < w * h; ++i) out[i] = d[i] == INT64_MAX ? kUnreachable : static_cast<int32_t>(d[i]);
  return out;
}

TEST(ExplorationTransformTest, EqualsBruteForceShortestPathsOnRandomGrids) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 20; ++trial) {
    const int w = 5 + trial * 2, h = 4 + trial;
    std::vector<uint8_t> trav(w * h), goal(w * h);
    std::bernoulli_distribution blocked(0.3), is_goal(0.03);
    for (int i = 0; i < w * h; ++i) {
      goal[i] = is_goal(rng);
      trav[i] = !goal[i] && !blocked(rng);
    }
    EXPECT_EQ(ComputeExplorationTransform(w, h, trav, goal), BruteForce(w, h, trav, goal)) << "trial " << trial;
  }
}

TEST(ExplorationTransformTest, EqualsBruteForceFromOpenToNearlyBlockedGrids) {
  // Obstacle densities from none to mostly blocked exercise every corner-cutting case of the
  // diagonal step; some goals are also marked traversable (the goal wins: cost 0).
  std::mt19937 rng(7);
  const double densities[] = {0.0, 0.1, 0.45, 0.7};
  for (double density : densities)
    for (int trial = 0; trial < 5; ++trial) {
      const int w = 3 + trial * 9, h = 30 - trial * 6;
      std::vector<uint8_t> trav(w * h), goal(w * h);
      std::bernoulli_distribution blocked(density), is_goal(0.02), also_traversable(0.5);
      for (int i = 0; i < w * h; ++i) {
        goal[i] = is_goal(rng);
        trav[i] = !blocked(rng) && (!goal[i] || also_traversable(rng));
      }
      EXPECT_EQ(ComputeExplorationTransform(w, h, trav, goal), BruteForce(w, h, trav, goal))
          << "density " << density << " trial " << trial;
    }
}

TEST(ExplorationTransformTest, FollowsAWindingCorridorToTheEnd) {
  // Walls on every other row with the gap alternating between the ends: one corridor that winds
  // back and forth, so the costs grow far beyond one crossing of the grid.
  const int w = 21, h = 21;
  std::vector<uint8_t> trav(w * h, 1), goal(w * h, 0);
  for (int y = 1; y < h; y += 2)
    for (int x = 0; x < w; ++x) trav[y * w + x] = x == ((y / 2) % 2 == 0 ? w - 1 : 0);
  goal[0] = 1;
  trav[0] = 0;
  const auto cost = ComputeExplorationTransform(w, h, trav, goal);
  EXPECT_EQ(cost, BruteForce(w, h, trav, goal));
  EXPECT_GT(cost[(h - 1) * w + (w - 1)], 10 * w * (h / 2));
}

TEST(ExplorationTransformTest, RoutesAroundAWallInsteadOfThroughIt) {
  // 9 x 5, goal at (8, 2), a wall at x = 4 except the gap at y = 4.
  const int w = 9, h = 5;
  std::vector<uint8_t> trav(w * h, 1), goal(w * h, 0);
  goal[2 * w + 8] = 1;
  trav[2 * w + 8] = 0;
  for (int y = 0; y < 4; ++y) trav[y * w + 4] = 0;
  const auto cost = ComputeExplorationTransform(w, h, trav, goal);
  // From (0, 2): straight through would be 80; around through (4, 4) it is longer.
  EXPECT_GT(cost[2 * w + 0], 80);
  EXPECT_EQ(cost[2 * w + 0], BruteForce(w, h, trav, goal)[2 * w + 0]);
  EXPECT_EQ(cost[0 * w + 4], kUnreachable);  // a wall cell
}

TEST(WeightedExplorationTransformTest, EqualsBruteForceOnRandomGridsAndTheUnweightedOneWithFactorsOfOne) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const int w = 5 + trial * 2, h = 4 + trial;
    std::vector<uint8_t> mask(w * h), factors(w * h), goal(w * h);
    std::bernoulli_distribution blocked(0.3), is_goal(0.03), heavy(0.3);
    std::uniform_int_distribution<int> weight(2, 9);
    for (int i = 0; i < w * h; ++i) {
      goal[i] = is_goal(rng);
      mask[i] = !goal[i] && !blocked(rng);
      factors[i] = mask[i] && heavy(rng) ? static_cast<uint8_t>(weight(rng)) : mask[i];
    }
    EXPECT_EQ(ComputeWeightedExplorationTransform(w, h, mask, goal), ComputeExplorationTransform(w, h, mask, goal))
        << "trial " << trial;
    EXPECT_EQ(ComputeWeightedExplorationTransform(w, h, factors, goal), BruteForce(w, h, factors, goal))
        << "trial " << trial;
  }
}

TEST(WeightedExplorationTransformTest, GoesRoundAHeavyBandWhenThatIsCheaper) {
  // 9 x 5, goal at (8, 2), a band of factor-3 cells at x = 4 except at y = 4: straight across
  // costs 120 (the two steps into and out of the band 30 each), round through (4, 4) 96.
  const int w = 9, h = 5;
  std::vector<uint8_t> factors(w * h, 1), goal(w * h, 0);
  goal[2 * w + 8] = 1;
  for (int y = 0; y < 4; ++y) factors[y * w + 4] = 3;
  const auto cost = ComputeWeightedExplorationTransform(w, h, factors, goal);
  EXPECT_EQ(cost[2 * w + 0], BruteForce(w, h, factors, goal)[2 * w + 0]);
  EXPECT_EQ(cost[2 * w + 0], 96);
  factors[4 * w + 4] = 3;  // the whole band heavy: straight across is cheapest
  EXPECT_EQ(ComputeWeightedExplorationTransform(w, h, factors, goal)[2 * w + 0], 120);
  EXPECT_THROW(ComputeWeightedExplorationTransform(w, h - 1, factors, goal), std::invalid_argument);
}

TEST(WeightedExplorationTransformTest, RefusesAGridOnlyWhenItsDearestStepCouldOverflow) {
  // 700,000 cells: costs fit at factor 1 (14 a step), not at 255 (2^31 / (14 x 255) is 601,536).
  const int w = 1000, h = 700;
  std::vector<uint8_t> factors(w * h, 1), goal(w * h, 0);
  goal[0] = 1;
  EXPECT_EQ(ComputeWeightedExplorationTransform(w, h, factors, goal)[1], 10);
  factors[w * h - 1] = 255;
  EXPECT_THROW(ComputeWeightedExplorationTransform(w, h, factors, goal), std::invalid_argument);
}

TEST(ExplorationTransformTest, NoGoalsMeansNothingIsReachable) {
  std::vector<uint8_t> trav(12, 1), goal(12, 0);
  for (int32_t c : ComputeExplorationTransform(4, 3, trav, goal)) EXPECT_EQ(c, kUnreachable);
}

TEST(ExplorationTransformTest, RejectsMismatchedMasks) {
  std::vector<uint8_t> trav(12, 1), goal(11, 0);
  EXPECT_THROW(ComputeExplorationTransform(4, 3, trav, goal), std::invalid_argument);
  EXPECT_THROW(ComputeExplorationTransform(0, 3, {}, {}), std::invalid_argument);
}

TEST(ExplorationTransformTest, RejectsGridsTooLargeFor32BitCosts) {
  // 20000 x 20000 cells: the longest path could cost more than an int32 holds. Refused before the
  // masks are looked at, so empty spans suffice here.
  EXPECT_THROW(ComputeExplorationTransform(20000, 20000, {}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::explorer
