// Pose-cell cost per camera frame (ProcessFrame: view injection, excite/inhibit/normalise, path
// integration, best pose, action). BM_PoseCellFrame*: St Lucia-like odometry (6-8 m/s at 10 Hz,
// gentle turns) with a random old view every fifth frame (far injections: a pessimistic case,
// the active region keeps several packets). BM_PoseCellFrameRevisit*: a route driven again.
// BM_RegisterBoundaries: the floor-boundary check of one loop closure (exp_boundary_check),
// two scans of a corner with range(0) points each (the demo's camera sees at most 61); 180 and
// 360 are the sizes exp_submap_offset registers (30 frames' boundaries thinned to 4-cm cells: a
// demo run's 190 old places averaged 178 and 151 points, at most 375 and 326).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "services/pose_cells/boundary_match.h"
#include "services/pose_cells/pose_cell_network.h"

namespace {

void RunPoseCellFrames(benchmark::State& state, int dim_xy, double cell_size_m) {
  rslam::pose_cells::PoseCellConfig cfg;
  cfg.pc_dim_xy = dim_xy;
  cfg.pc_cell_x_size = cell_size_m;
  rslam::pose_cells::PoseCellNetwork net(cfg);
  uint32_t next_template = 0;
  int frame = 0;
  // Warm up into a steady state with some templates learnt.
  auto one_frame = [&] {
    const double vtrans = 6.0 + 2.0 * std::sin(frame * 0.01);
    const double vrot = 0.15 * std::sin(frame * 0.037);
    uint32_t tid;
    bool is_new;
    if (frame % 5 == 4 && next_template > 40) {
      tid = (frame * 7) % (next_template - 20);
      is_new = false;
    } else {
      tid = next_template++;
      is_new = true;
    }
    ++frame;
    return net.ProcessFrame(vtrans, vrot, 0.1, {tid, is_new, 0.0});
  };
  for (int i = 0; i < 500; ++i) one_frame();
  for (auto _ : state) benchmark::DoNotOptimize(one_frame());
  state.counters["active_cells"] = net.ActiveCellCount();
  state.counters["region_cells"] = net.ActiveRegionCells();
  state.counters["experiences"] = net.experience_count();
}

// Revisiting a route: a 300-frame lap (8 m/s, 10 Hz, constant turn) learnt on the first lap;
// later laps see the template of the same place every frame (injections next to the packet),
// plus an unrelated old view every 50th frame (a far injection, like a false loop closure).
void RunPoseCellRevisits(benchmark::State& state, int dim_xy, double cell_size_m) {
  rslam::pose_cells::PoseCellConfig cfg;
  cfg.pc_dim_xy = dim_xy;
  cfg.pc_cell_x_size = cell_size_m;
  rslam::pose_cells::PoseCellNetwork net(cfg);
  constexpr int kLap = 300;
  const double vrot = 2.0 * 3.14159265358979 / (kLap * 0.1);
  int frame = 0;
  auto one_frame = [&] {
    const int j = frame % kLap;
    uint32_t tid = static_cast<uint32_t>(j);
    bool is_new = frame < kLap;
    if (!is_new && frame % 50 == 49) tid = static_cast<uint32_t>((j + kLap / 2) % kLap);
    ++frame;
    return net.ProcessFrame(8.0, vrot, 0.1, {tid, is_new, 0.0});
  };
  for (int i = 0; i < 2 * kLap; ++i) one_frame();
  for (auto _ : state) benchmark::DoNotOptimize(one_frame());
  state.counters["active_cells"] = net.ActiveCellCount();
  state.counters["region_cells"] = net.ActiveRegionCells();
  state.counters["experiences"] = net.experience_count();
}

void BM_PoseCellFrameStLucia30x30x36(benchmark::State& state) { RunPoseCellFrames(state, 30, 2.0); }
void BM_PoseCellFrameDefault21x21x36(benchmark::State& state) { RunPoseCellFrames(state, 21, 1.0); }
void BM_PoseCellFrameRevisitStLucia30x30x36(benchmark::State& state) { RunPoseCellRevisits(state, 30, 2.0); }
void BM_PoseCellFrameRevisitDefault21x21x36(benchmark::State& state) { RunPoseCellRevisits(state, 21, 1.0); }

// A fixed number of frames: the network's state (how many packets, how large the active region)
// depends on how far the drive has gone, so a time-based iteration count would measure a
// different stretch of it on a faster or busier machine.
constexpr int kMeasuredFrames = 3000;
BENCHMARK(BM_PoseCellFrameStLucia30x30x36)->Iterations(kMeasuredFrames)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PoseCellFrameDefault21x21x36)->Iterations(kMeasuredFrames)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PoseCellFrameRevisitStLucia30x30x36)->Iterations(kMeasuredFrames)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PoseCellFrameRevisitDefault21x21x36)->Iterations(kMeasuredFrames)->Unit(benchmark::kMicrosecond);

// n points over 60 degrees of a corner (a wall across 1.5 m ahead, one 0.8 m to the left), moved
// back by shift_m (the same corner seen from shift_m further on).
std::vector<Eigen::Vector2f> Corner(int n, double shift_m) {
  std::vector<Eigen::Vector2f> points;
  for (int i = 0; i < n; ++i) {
    const double b = (-30.0 + 60.0 * i / std::max(1, n - 1)) * M_PI / 180.0, c = std::cos(b), s = std::sin(b);
    const double r = std::min(1.5 / c, s > 0 ? 0.8 / s : 1e9);
    points.emplace_back(static_cast<float>(r * c - shift_m), static_cast<float>(r * s));
  }
  return points;
}

void BM_RegisterBoundaries(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto stored = Corner(n, 0.0), current = Corner(n, 0.3);
  for (auto _ : state) benchmark::DoNotOptimize(rslam::pose_cells::RegisterBoundaries(stored, current));
}
BENCHMARK(BM_RegisterBoundaries)->Arg(8)->Arg(30)->Arg(61)->Arg(180)->Arg(360)->Unit(benchmark::kMicrosecond);

}  // namespace
