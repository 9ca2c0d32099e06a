// Explorer hot paths: the exploration transform on a 500x500 grid (target < 5 ms) and one full
// plan (configuration space + transform + path) on the uwb-room map.

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "services/explorer/exploration_planner.h"
#include "services/explorer/exploration_transform.h"

namespace rslam::explorer {
namespace {

void BM_ExplorationTransform500(benchmark::State& state) {
  const int n = 500;
  std::vector<uint8_t> traversable(n * n), goal(n * n, 0);
  std::mt19937 rng(7);
  std::bernoulli_distribution obstacle(0.2);
  for (int i = 0; i < n * n; ++i) traversable[i] = !obstacle(rng);
  // Unknown space: the right tenth of the map.
  for (int y = 0; y < n; ++y)
    for (int x = n - n / 10; x < n; ++x) {
      goal[y * n + x] = 1;
      traversable[y * n + x] = 0;
    }
  for (auto _ : state) {
    auto cost = ComputeExplorationTransform(n, n, traversable, goal);
    benchmark::DoNotOptimize(cost.data());
  }
  state.SetItemsProcessed(state.iterations() * n * n);
}
BENCHMARK(BM_ExplorationTransform500)->Unit(benchmark::kMillisecond);

void BM_PlanFromOnUwbRoom(benchmark::State& state) {
  const char* env = std::getenv("RSLAM_SHARED_DATA");
  const std::filesystem::path data = env ? env : std::filesystem::path(RSLAM_SOURCE_DIR) / "../shared/data";
  const cv::Mat image = cv::imread((data / "worlds/uwb-room.pgm").string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    state.SkipWithError("worlds/uwb-room.pgm not found (set RSLAM_SHARED_DATA)");
    return;
  }
  // Half of the map known (as the true map), the rest unknown: a mid-exploration state.
  std::vector<int8_t> cells(image.total());
  for (int r = 0; r < image.rows; ++r)
    for (int c = 0; c < image.cols; ++c) {
      const uchar v = image.at<uchar>(r, c);
      cells[(image.rows - 1 - r) * image.cols + c] = c > image.cols / 2 ? -1 : (v >= 250 ? 0 : (v <= 50 ? 100 : -1));
    }
  const GridView view{image.cols, image.rows, 0.04, -10.0, -10.0, cells};
  ExplorationPlanner planner(ExplorerConfig{});
  for (auto _ : state) {
    Plan plan = planner.PlanFrom(view, {2.0, 3.0, 0.0});
    benchmark::DoNotOptimize(plan.commands.data());
  }
}
BENCHMARK(BM_PlanFromOnUwbRoom)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rslam::explorer
