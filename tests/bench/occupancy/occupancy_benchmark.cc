// Occupancy mapper hot paths: log-odds grid updates (target >= 50 M cell updates/s), the
// Radial Obstacle Profile from one 320x240 frame (target < 1 ms: segmentation + IPM + profile),
// and the rebuild of the grid after a map correction (the replay of every kept profile, on the
// rebuild thread, against what stays on the frame's thread).

#include <benchmark/benchmark.h>

#include <cmath>
#include <optional>

#include "services/occupancy/anchored_profile_map.h"
#include "services/occupancy/camera_model.h"
#include "services/occupancy/floor_segmenter.h"
#include "services/occupancy/occupancy_grid.h"
#include "services/occupancy/profile_alignment.h"
#include "services/occupancy/radial_obstacle_profile.h"
#include "tests/unit/occupancy/synthetic_scene.h"

namespace rslam::occupancy {
namespace {

// A 360-bin pirouette profile: obstacles at 60-100 % of max_range, every 7th bin free.
RadialObstacleProfile PirouetteProfile(double max_range) {
  RadialObstacleProfile p;
  p.first_bearing_rad = -M_PI;
  p.bin_width_rad = M_PI / 180.0;
  for (int i = 0; i < 360; ++i) {
    const float r = static_cast<float>(max_range * (0.6 + 0.4 * std::abs(std::sin(i * 0.05))));
    p.bins.push_back(RopBin{i % 7 == 0 ? static_cast<float>(max_range) : r, 0.07f,
                            i % 7 == 0 ? BinStatus::kFree : BinStatus::kObstacle});
  }
  return p;
}

// A 40 m x 40 m grid around the origin (the demo's) of `cell_mm` cells.
GridConfig DemoGrid(int64_t cell_mm) {
  const int cells = static_cast<int>(40000 / cell_mm);
  return GridConfig{cell_mm / 1000.0, cells, cells, -20.0, -20.0};
}

// Aligning a camera's profile (60 one-degree bins of the pirouette profile, obstacles at 0.9-1.5 m)
// with a grid where the place was seen three times. args: 0 placed where it was taken (only the
// misplaced-points check runs) or 1 placed 0.2 m short of the walls (the 0.3 m, 0.1 rad search runs
// over whole cells and 0.033 rad, 13 x 13 x 7 poses on 5-cm cells and 25 x 25 x 7 on 2.5-cm ones,
// then 27 around the best); cell size (mm; the demo's 25).
void BM_AlignProfile(benchmark::State& state) {
  SensorModelConfig sensor;
  sensor.reliable_range_m = 1.5;
  OccupancyGrid grid(DemoGrid(state.range(1)), sensor);
  const RadialObstacleProfile all = PirouetteProfile(1.5);
  for (int i = 0; i < 3; ++i) grid.InsertProfile(all, {0.0, 0.0, 0.0});
  RadialObstacleProfile camera = all;
  camera.first_bearing_rad = all.BinCentre(150) - 0.5 * all.bin_width_rad;
  camera.bins.assign(all.bins.begin() + 150, all.bins.begin() + 210);
  ProfileAlignmentConfig config;
  config.window_m = 0.3;
  const Pose2D placed = state.range(0) ? Pose2D{-0.2, 0.0, 0.0} : Pose2D{0.0, 0.0, 0.0};
  int64_t moved = 0;
  for (auto _ : state) moved += AlignProfile(grid, camera, placed, config).has_value();
  state.counters["aligned"] = static_cast<double>(moved) / std::max<int64_t>(state.iterations(), 1);
}
BENCHMARK(BM_AlignProfile)->ArgsProduct({{0, 1}, {50, 25}})->Unit(benchmark::kMicrosecond);

// args: cell size (mm), reliable range (cm)
void BM_GridInsertProfile(benchmark::State& state) {
  const double resolution = state.range(0) / 1000.0, range = state.range(1) / 100.0;
  SensorModelConfig sensor;
  sensor.reliable_range_m = range;
  OccupancyGrid grid(GridConfig{resolution, 2000, 2000, -10.0, -10.0}, sensor);
  const RadialObstacleProfile profile = PirouetteProfile(range);
  int64_t cells = 0;
  int i = 0;
  for (auto _ : state) {
    const Pose2D pose{std::fmod(i * 0.037, 4.0) - 2.0, std::fmod(i * 0.053, 4.0) - 2.0, i * 0.1};
    cells += grid.InsertProfile(profile, pose);
    ++i;
  }
  state.SetItemsProcessed(cells);
  state.counters["cells_per_profile"] = static_cast<double>(cells) / std::max(i, 1);
}
BENCHMARK(BM_GridInsertProfile)->Args({10, 40})->Args({10, 200})->Args({40, 400});

// The grid as published (ROS cells, every grid_publish_every_n_frames frames on the frame's
// thread). arg: cell size (mm) of the demo's 40 m x 40 m grid.
void BM_GridToRosCells(benchmark::State& state) {
  SensorModelConfig sensor;
  sensor.reliable_range_m = 1.5;
  OccupancyGrid grid(DemoGrid(state.range(0)), sensor);
  const RadialObstacleProfile profile = PirouetteProfile(1.5);
  for (int i = 0; i < 200; ++i)
    grid.InsertProfile(profile, {std::fmod(i * 0.37, 10.0), std::fmod(i * 0.53, 8.0), i * 0.1});
  for (auto _ : state) {
    std::vector<int8_t> cells = grid.ToRosCells();
    benchmark::DoNotOptimize(cells.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(grid.width()) * grid.height());
}
BENCHMARK(BM_GridToRosCells)->Arg(50)->Arg(25)->Unit(benchmark::kMillisecond);

struct Pipeline {
  CameraConfig camera;
  CameraModel model{camera};
  InversePerspectiveMap ipm{camera};
  RopExtractor extractor{RopConfig{}, ipm};
  FloorSegmenter segmenter{FloorSegmenterConfig{}, testing::kFloorColour};
  cv::Mat frame;
  Pipeline() {
    std::vector<testing::Wall> walls = testing::SquareRoom(0.45);
    for (const auto& w : testing::Box(0.2, 0.05, 0.27, 0.12, 0.08, {30, 30, 200})) walls.push_back(w);
    frame = testing::Render(camera, {0.05, 0.0, 0.2}, walls, 3.0, 1, {{0.2, 0.05, 0.27, 0.12, 0.08, {30, 30, 200}}}).image;
  }
};

void BM_RopFromFrame(benchmark::State& state) {
  Pipeline p;
  for (auto _ : state) {
    RadialObstacleProfile rop = p.extractor.Extract(p.segmenter.Segment(p.frame));
    benchmark::DoNotOptimize(rop.bins.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RopFromFrame)->Unit(benchmark::kMicrosecond);

void BM_RopFromRawFrameWithCorrection(benchmark::State& state) {
  Pipeline p;
  for (auto _ : state) {
    RadialObstacleProfile rop = p.extractor.Extract(p.segmenter.Segment(p.model.Correct(p.frame)));
    benchmark::DoNotOptimize(rop.bins.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RopFromRawFrameWithCorrection)->Unit(benchmark::kMicrosecond);

// n frame-like profiles (70 bins over 1.2 rad, walls 1-2 m away) on 100 experiences scattered over
// a 10 m x 8 m room, in a 40 m x 40 m grid of `cell_mm` cells (the demo's: 25).
AnchoredProfileMap DemoSizedMap(int n, int64_t cell_mm) {
  SensorModelConfig sensor;
  sensor.reliable_range_m = 2.0;
  AnchoredProfileMap map(DemoGrid(cell_mm), sensor);
  RadialObstacleProfile frame;
  frame.first_bearing_rad = -0.6;
  frame.bin_width_rad = 1.2 / 70;
  for (int i = 0; i < 70; ++i)
    frame.bins.push_back(
        RopBin{static_cast<float>(1.0 + 0.5 * (1 + std::sin(i * 0.2))), 0.35f, BinStatus::kObstacle});
  for (int i = 0; i < n; ++i) {
    const Pose2D experience{std::fmod(i * 0.37, 10.0), std::fmod(i * 0.53, 8.0), i * 0.1};
    map.AddProfile({static_cast<uint64_t>(i % 100), {0.05 * (i % 7), 0.0, 0.3 * (i % 11)}, experience, frame, {}});
  }
  return map;
}

std::optional<Pose2D> Shifted(uint64_t id) { return Pose2D{0.01 * static_cast<double>(id), 0.02, 0.001}; }

// args: profiles, cell size (mm)
void BM_AnchoredProfileMapReplay(benchmark::State& state) {
  AnchoredProfileMap map = DemoSizedMap(static_cast<int>(state.range(0)), state.range(1));
  AnchoredProfileMap::RebuildPlan plan = map.PlanRebuild(Shifted);
  for (auto _ : state) {
    std::optional<OccupancyGrid> grid = AnchoredProfileMap::Replay(plan);
    benchmark::DoNotOptimize(grid->values().data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_AnchoredProfileMapReplay)
    ->ArgsProduct({{1000, 10000, 20000}, {50, 25}})
    ->Unit(benchmark::kMillisecond);

// What a rebuild leaves on the frame's thread: the plan and the adopt of a replayed grid.
void BM_AnchoredProfileMapPlanAndAdopt(benchmark::State& state) {
  AnchoredProfileMap map = DemoSizedMap(static_cast<int>(state.range(0)), state.range(1));
  AnchoredProfileMap::RebuildPlan first = map.PlanRebuild(Shifted);
  const OccupancyGrid replayed = *AnchoredProfileMap::Replay(first);
  for (auto _ : state) {
    const AnchoredProfileMap::RebuildPlan plan = map.PlanRebuild(Shifted);
    OccupancyGrid grid = replayed;  // the copy stands in for the replay (not timed apart)
    map.Adopt(std::move(grid), plan);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_AnchoredProfileMapPlanAndAdopt)
    ->ArgsProduct({{1000, 10000, 20000}, {50, 25}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rslam::occupancy
