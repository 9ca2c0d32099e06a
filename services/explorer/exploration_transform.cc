#include "services/explorer/exploration_transform.h"

#include <algorithm>
#include <array>
#include <functional>
#include <queue>
#include <stdexcept>
#include <utility>

namespace rslam::explorer {
namespace {

// Cost grid encoding: blocked cells (and the one-cell border) hold -1, so the relaxation test
// `new_cost < cost[neighbour]` fails for them and for goals (0) without looking at a mask, and a
// cell is open (may be passed beside on a diagonal step) exactly when its cost is >= 0.
constexpr int32_t kBlockedCell = -1;
// Dial's algorithm: edge costs are at most 14, so a ring of 15 buckets holds every pending cost.
constexpr int kRing = kDiagonalStepCost + 1;

// The cells queued at one cost level. Grown only between levels, so pushes inside a level are a
// store and a pointer bump.
struct Bucket {
  std::vector<int32_t> cells;
  size_t size = 0;
  void MakeRoomFor(size_t more) {
    if (size + more > cells.size()) cells.resize(std::max<size_t>(256, 2 * (size + more)));
  }
  int32_t* end() { return cells.data() + size; }
  void SetEnd(const int32_t* e) { size = static_cast<size_t>(e - cells.data()); }
};

// Lowers the eight neighbours of cell i (whose settled cost is `from`) where that is shorter and
// queues the lowered ones. Written without branches: on maps with scattered obstacles whether a
// neighbour improves is unpredictable, and mispredictions dominated the branchy version.
inline void RelaxNeighbours(int32_t* cost, int32_t i, int32_t row, int32_t from, int32_t*& straight_queue,
                            int32_t*& diagonal_queue) {
  const int32_t straight_cost = from + kStraightStepCost;
  const int32_t diagonal_cost = from + kDiagonalStepCost;
  const int32_t east = cost[i + 1], west = cost[i - 1], north = cost[i + row], south = cost[i - row];
  const auto relax_straight = [&](int32_t neighbour, int32_t old_cost) {
    const bool better = straight_cost < old_cost;
    cost[neighbour] = better ? straight_cost : old_cost;
    *straight_queue = neighbour;
    straight_queue += better;
  };
  relax_straight(i + 1, east);
  relax_straight(i - 1, west);
  relax_straight(i + row, north);
  relax_straight(i - row, south);
  // A diagonal step needs both cells it passes between open (not blocked), so it never cuts a corner.
  const auto relax_diagonal = [&](int32_t neighbour, bool corners_open) {
    const int32_t old_cost = cost[neighbour];
    const bool better = corners_open & (diagonal_cost < old_cost);
    cost[neighbour] = better ? diagonal_cost : old_cost;
    *diagonal_queue = neighbour;
    diagonal_queue += better;
  };
  const bool east_open = east >= 0, west_open = west >= 0, north_open = north >= 0, south_open = south >= 0;
  relax_diagonal(i + row + 1, north_open & east_open);
  relax_diagonal(i + row - 1, north_open & west_open);
  relax_diagonal(i - row + 1, south_open & east_open);
  relax_diagonal(i - row - 1, south_open & west_open);
}

}  // namespace

std::vector<int32_t> ComputeExplorationTransform(int width, int height, std::span<const uint8_t> traversable,
                                                 std::span<const uint8_t> goal) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("exploration grid has no cells");
  // Costs and cell indices are 32-bit: a path visits each cell at most once, so no cost exceeds
  // kDiagonalStepCost per cell, and every cost must stay below kUnreachable.
  if ((int64_t{width} + 2) * (int64_t{height} + 2) > kUnreachable / kDiagonalStepCost)
    throw std::invalid_argument("exploration grid is too large for 32-bit costs");
  const size_t n = static_cast<size_t>(width) * height;
  if (traversable.size() != n || goal.size() != n)
    throw std::invalid_argument("exploration grid masks do not match width x height");
  // The wave runs on a padded grid (one blocked cell all round, so neighbours need no bounds
  // checks) held in the result vector itself, which is compacted to width x height at the end:
  // one allocation per call.
  const int32_t row = width + 2;
  const size_t padded_cells = static_cast<size_t>(row) * (height + 2);
  std::vector<int32_t> result(padded_cells);
  int32_t* const cost = result.data();
  std::fill_n(cost, row, kBlockedCell);
  std::fill_n(cost + padded_cells - row, row, kBlockedCell);
  for (int y = 0; y < height; ++y) {
    int32_t* padded_row = cost + static_cast<size_t>(y + 1) * row;
    const uint8_t* t = traversable.data() + static_cast<size_t>(y) * width;
    const uint8_t* g = goal.data() + static_cast<size_t>(y) * width;
    padded_row[0] = kBlockedCell;
    padded_row[width + 1] = kBlockedCell;
    for (int x = 0; x < width; ++x) padded_row[x + 1] = g[x] ? 0 : (t[x] ? kUnreachable : kBlockedCell);
  }

  std::array<Bucket, kRing> buckets;
  // Cost level 0 (the goals) is expanded in raster order straight from the grid rather than
  // through a bucket: there can be as many goals as cells, and the scan is cache friendly.
  {
    Bucket& straight_bucket = buckets[kStraightStepCost];
    Bucket& diagonal_bucket = buckets[kDiagonalStepCost];
    for (int y = 0; y < height; ++y) {
      straight_bucket.MakeRoomFor(4 * static_cast<size_t>(width));
      diagonal_bucket.MakeRoomFor(4 * static_cast<size_t>(width));
      int32_t* straight_queue = straight_bucket.end();
      int32_t* diagonal_queue = diagonal_bucket.end();
      const int32_t first = (y + 1) * row + 1;
      for (int32_t i = first; i < first + width; ++i)
        if (cost[i] == 0) RelaxNeighbours(cost, i, row, 0, straight_queue, diagonal_queue);
      straight_bucket.SetEnd(straight_queue);
      diagonal_bucket.SetEnd(diagonal_queue);
    }
  }
  // Stops once a whole ring of buckets has come up empty: nothing is pending any more.
  int empty_buckets_in_a_row = 1;  // level 0 has no bucket
  for (int32_t current = 1; empty_buckets_in_a_row < kRing; ++current) {
    Bucket& bucket = buckets[current % kRing];
    if (bucket.size == 0) {
      ++empty_buckets_in_a_row;
      continue;
    }
    empty_buckets_in_a_row = 0;
    Bucket& straight_bucket = buckets[(current + kStraightStepCost) % kRing];
    Bucket& diagonal_bucket = buckets[(current + kDiagonalStepCost) % kRing];
    straight_bucket.MakeRoomFor(4 * bucket.size);
    diagonal_bucket.MakeRoomFor(4 * bucket.size);
    int32_t* straight_queue = straight_bucket.end();
    int32_t* diagonal_queue = diagonal_bucket.end();
    for (const int32_t* it = bucket.cells.data(), *end = bucket.end(); it != end; ++it) {
      // Skip stale entries (cells lowered again since they were queued): they were expanded at
      // their lower cost already.
      if (cost[*it] == current) RelaxNeighbours(cost, *it, row, current, straight_queue, diagonal_queue);
    }
    bucket.size = 0;
    straight_bucket.SetEnd(straight_queue);
    diagonal_bucket.SetEnd(diagonal_queue);
  }

  // Compact in place to width x height (each cell moves to a lower index, rows in order), blocked
  // cells becoming unreachable.
  for (int y = 0; y < height; ++y) {
    const int32_t* from = cost + static_cast<size_t>(y + 1) * row + 1;
    int32_t* to = cost + static_cast<size_t>(y) * width;
    for (int x = 0; x < width; ++x) to[x] = from[x] < 0 ? kUnreachable : from[x];
  }
  result.resize(n);
  return result;
}

std::vector<int32_t> ComputeWeightedExplorationTransform(int width, int height, std::span<const uint8_t> step_factor,
                                                         std::span<const uint8_t> goal) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("exploration grid has no cells");
  const size_t n = static_cast<size_t>(width) * height;
  if (step_factor.size() != n || goal.size() != n)
    throw std::invalid_argument("exploration grid masks do not match width x height");
  // A path visits each cell at most once, so no cost exceeds the dearest step per cell.
  const int64_t max_step_cost =
      int64_t{kDiagonalStepCost} * std::max<uint8_t>(1, *std::ranges::max_element(step_factor));
  if (static_cast<int64_t>(n) > kUnreachable / max_step_cost)
    throw std::invalid_argument("exploration grid is too large for 32-bit costs");
  const auto factor = [&](size_t i) -> int32_t {
    return goal[i] ? std::max<int32_t>(1, step_factor[i]) : step_factor[i];
  };
  std::vector<int32_t> cost(n, kUnreachable);
  using Entry = std::pair<int32_t, int32_t>;  // cost, cell
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (size_t i = 0; i < n; ++i)
    if (goal[i]) {
      cost[i] = 0;
      queue.push({0, static_cast<int32_t>(i)});
    }
  while (!queue.empty()) {
    const auto [from, i] = queue.top();
    queue.pop();
    if (from != cost[static_cast<size_t>(i)]) continue;  // lowered again since it was queued
    const int x = i % width, y = i / width;
    const int32_t f = factor(static_cast<size_t>(i));
    const auto open = [&](int cx, int cy) { return factor(static_cast<size_t>(cy) * width + cx) > 0; };
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
        const size_t j = static_cast<size_t>(ny) * width + nx;
        if (goal[j] || step_factor[j] == 0) continue;  // sources, and cells the wave may not enter
        const bool diagonal = dx != 0 && dy != 0;
        if (diagonal && !(open(nx, y) && open(x, ny))) continue;  // never cut a corner
        const int32_t c = from + (diagonal ? kDiagonalStepCost : kStraightStepCost) * std::max(f, factor(j));
        if (c < cost[j]) {
          cost[j] = c;
          queue.push({c, static_cast<int32_t>(j)});
        }
      }
  }
  return cost;
}

}  // namespace rslam::explorer
