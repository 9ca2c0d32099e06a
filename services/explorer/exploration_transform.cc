#include "services/explorer/exploration_transform.h"

#include <algorithm>
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
  // Padded copy (one blocked cell all round) so the inner loop needs no bounds checks.
  const int pw = width + 2, ph = height + 2;
  enum : uint8_t { kBlocked = 0, kTraversable = 1, kGoal = 2 };
  // Cost and state side by side: each neighbour test touches one cache line.
  struct Cell {
    int32_t cost = kUnreachable;
    uint8_t state = kBlocked;
  };
  std::vector<Cell> cells(static_cast<size_t>(pw) * ph);
  // Dial's algorithm: edge costs are at most 14, so a ring of 15 buckets holds every pending cost.
  constexpr int kRing = kDiagonalStepCost + 1;
  std::array<std::vector<int32_t>, kRing> buckets;
  for (auto& b : buckets) b.reserve(static_cast<size_t>(width + height) * 4);
  int empty_buckets_in_a_row = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const size_t i = static_cast<size_t>(y) * width + x;
      const int32_t p = (y + 1) * pw + x + 1;
      if (goal[i]) {
        cells[p] = {0, kGoal};
        buckets[0].push_back(p);
      } else if (traversable[i]) {
        cells[p].state = kTraversable;
      }
    }
  const int32_t straight[4] = {1, -1, pw, -pw};
  // Diagonal offset and the two orthogonal cells it passes between.
  const int32_t diagonal[4][3] = {{pw + 1, 1, pw}, {pw - 1, -1, pw}, {-pw + 1, 1, -pw}, {-pw - 1, -1, -pw}};
  // Stops once a whole ring of buckets has come up empty: nothing is pending any more.
  for (int32_t current = 0; empty_buckets_in_a_row < kRing; ++current) {
    std::vector<int32_t>& bucket = buckets[current % kRing];
    empty_buckets_in_a_row = bucket.empty() ? empty_buckets_in_a_row + 1 : 0;
    std::vector<int32_t>& straight_bucket = buckets[(current + kStraightStepCost) % kRing];
    std::vector<int32_t>& diagonal_bucket = buckets[(current + kDiagonalStepCost) % kRing];
    while (!bucket.empty()) {
      const int32_t i = bucket.back();
      bucket.pop_back();
      if (cells[i].cost != current) continue;  // a stale entry, improved since it was queued
      const int32_t straight_cost = current + kStraightStepCost;
      for (int32_t off : straight) {
        const int32_t ni = i + off;
        Cell& next = cells[ni];
        if (next.state == kTraversable && straight_cost < next.cost) {
          next.cost = straight_cost;
          straight_bucket.push_back(ni);
        }
      }
      const int32_t diagonal_cost = current + kDiagonalStepCost;
      for (const auto& d : diagonal) {
        const int32_t ni = i + d[0];
        Cell& next = cells[ni];
        if (next.state == kTraversable && diagonal_cost < next.cost && cells[i + d[1]].state != kBlocked &&
            cells[i + d[2]].state != kBlocked) {
          next.cost = diagonal_cost;
          diagonal_bucket.push_back(ni);
        }
      }
    }
  }
  std::vector<int32_t> cost(n);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) cost[static_cast<size_t>(y) * width + x] = cells[(y + 1) * pw + x + 1].cost;
  return cost;
}

}  // namespace rslam::explorer
