#include "services/explorer/exploration_transform.h"

#include <array>
#include <stdexcept>

namespace rslam::explorer {

std::vector<int32_t> ComputeExplorationTransform(int width, int height,
                                                 std::span<const uint8_t> traversable,
                                                 std::span<const uint8_t> goal) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("exploration grid has no cells");
  const size_t n = static_cast<size_t>(width) * height;
  if (traversable.size() != n || goal.size() != n)
    throw std::invalid_argument("exploration grid masks do not match width x height");
  std::vector<int32_t> cost(n, kUnreachable);
  // Dial's algorithm: edge costs are at most 14, so a ring of 15 buckets holds every pending cost.
  constexpr int kRing = kDiagonalStepCost + 1;
  std::array<std::vector<int32_t>, kRing> buckets;
  size_t pending = 0;
  for (size_t i = 0; i < n; ++i)
    if (goal[i]) {
      cost[i] = 0;
      buckets[0].push_back(static_cast<int32_t>(i));
      ++pending;
    }
  auto open = [&](int x, int y) {
    const size_t i = static_cast<size_t>(y) * width + x;
    return traversable[i] || goal[i];
  };
  for (int32_t current = 0; pending > 0; ++current) {
    std::vector<int32_t>& bucket = buckets[current % kRing];
    while (!bucket.empty()) {
      const int32_t i = bucket.back();
      bucket.pop_back();
      --pending;
      if (cost[i] != current) continue;  // a stale entry, improved since it was queued
      const int x = i % width, y = i / width;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
          const int32_t ni = ny * width + nx;
          if (!traversable[ni]) continue;
          const bool diagonal = dx != 0 && dy != 0;
          if (diagonal && !(open(x + dx, y) && open(x, y + dy))) continue;
          const int32_t candidate = current + (diagonal ? kDiagonalStepCost : kStraightStepCost);
          if (candidate < cost[ni]) {
            cost[ni] = candidate;
            buckets[candidate % kRing].push_back(ni);
            ++pending;
          }
        }
      }
    }
  }
  return cost;
}

}  // namespace rslam::explorer
