#pragma once
// The exploration transform of paper 003 section 4: a distance transform whose sources are all
// unknown (goal) cells and which spreads only through traversable cells, so distances route
// around obstacles (OpenCV's distanceTransform measures straight through them; Borgefors'
// two-pass chamfer needs repeated passes on maps with obstacles, as the paper notes citing
// Jarvis). It is computed exactly as a shortest-path problem with 8-neighbour chamfer costs
// (10 straight, 14 diagonal) by Dial's bucket queue, O(cells). A diagonal step is allowed only
// when both cells it passes between are open, so paths never cut obstacle corners.
// Descending the transform from the robot's cell gives the shortest path to the nearest unknown.

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace rslam::explorer {

inline constexpr int32_t kStraightStepCost = 10;
inline constexpr int32_t kDiagonalStepCost = 14;
inline constexpr int32_t kUnreachable = std::numeric_limits<int32_t>::max();

// traversable[i] != 0: the wave may enter cell i; goal[i] != 0: cell i is a source (cost 0).
// Returns the cost per cell (kUnreachable where no goal can be reached). Throws
// std::invalid_argument if the spans do not hold width x height cells, or if the grid is too large
// for 32-bit costs (more than about 150 million cells).
std::vector<int32_t> ComputeExplorationTransform(int width, int height,
                                                 std::span<const uint8_t> traversable,
                                                 std::span<const uint8_t> goal);

// The same with steps of unequal cost: a step costs its chamfer cost times the larger
// step_factor of the two cells it joins (a goal cell's factor counts as at least 1), and
// step_factor[i] == 0 keeps the wave out of cell i as traversable[i] == 0 does above. With every
// open cell's factor 1 it equals ComputeExplorationTransform. The explorer weighs the dilation
// margin so when it plans through it (ExplorerConfig::margin_step_cost); that is rare, so this is
// plain Dijkstra on a binary heap, not the bucket queue above. Throws as above (too large:
// more cells than 2^31 / (14 x the largest factor), about 7.6 million at factor 20).
std::vector<int32_t> ComputeWeightedExplorationTransform(int width, int height,
                                                         std::span<const uint8_t> step_factor,
                                                         std::span<const uint8_t> goal);

}  // namespace rslam::explorer
