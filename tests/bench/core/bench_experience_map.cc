// Experience-map cost per camera frame (Integrate + Apply of a kSet or, every tenth frame, a
// kLink loop closure + that frame's correction budget) on maps of 1,000 / 10,000 / 100,000
// experiences: laps of 100 experiences around a circle, linked along the laps, to the same place
// on the previous lap every tenth experience, with link noise so correction always has work.
// BM_ExperienceMapFrameFullRelaxation is OpenRatSLAM's behaviour (10 full sweeps per action);
// BM_ExperienceMapFrameLeastSquares corrects by least squares (pose_graph.h) every 50 frames
// instead, and BM_ExperienceMapLeastSquaresCorrection is one such correction (2 Gauss-Newton
// steps over the whole map); ...WithWalls the same with every experience's wall direction held to
// the building's axes (exp_manhattan_sigma_rad). BM_RegisterScans registers two stretches' floor
// boundaries of n points each (exp_scan_links: scan_registration.h) from a guess 0.1 m and 0.03
// rad off, as the map does for every fifth experience that has an old one near it.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "services/experience_map/experience_map.h"
#include "services/experience_map/scan_registration.h"

namespace {

using rslam::experience_map::ExperienceAction;
using rslam::experience_map::ExperienceMap;
using rslam::experience_map::ExperienceMapConfig;
namespace pb = rslam::experience_map::proto;

pb::ExperienceMap BuildLaps(int n, bool walls = false) {
  constexpr int kLap = 100;
  const double step = 2.0 * std::numbers::pi / kLap;
  const double radius = 50.0;
  const double chord = 2.0 * radius * std::sin(step / 2.0);
  pb::ExperienceMap m;
  uint32_t seed = 12345;
  auto noise = [&seed] {  // deterministic, in [-0.5, 0.5)
    seed = seed * 1664525u + 1013904223u;
    return (seed >> 8) / static_cast<double>(1u << 24) - 0.5;
  };
  for (int i = 0; i < n; ++i) {
    const double a = i * step;
    auto* e = m.add_experiences();
    e->set_x_m(radius * std::cos(a) + 0.3 * noise());
    e->set_y_m(radius * std::sin(a) + 0.3 * noise());
    e->set_th_rad(std::remainder(a + std::numbers::pi / 2, 2 * std::numbers::pi));
    e->set_template_id(i);
    if (walls) e->set_wall_rad(std::remainder(-e->th_rad() + 0.05 * noise(), std::numbers::pi / 2));
  }
  m.set_has_manhattan_axes(walls);
  auto link = [&](int from, int to, double d, double heading, double facing) {
    auto* l = m.add_links();
    l->set_from_id(from);
    l->set_to_id(to);
    l->set_d_m(d);
    l->set_heading_rad(heading);
    l->set_facing_rad(facing);
    l->set_travel_time_s(d);
    l->set_traversals(1);
  };
  for (int i = 0; i < n; ++i) {
    link(i, (i + 1) % n, chord * (1.0 + 0.02 * noise()), step / 2.0 + 0.01 * noise(), step + 0.01 * noise());
    if (i >= kLap && i % 10 == 0) link(i, i - kLap, 0.0, 0.0, 0.0);
  }
  m.set_has_current(true);
  m.set_current_id(0);
  return m;
}

void RunFrames(benchmark::State& state, const ExperienceMapConfig& cfg) {
  const int n = static_cast<int>(state.range(0));
  ExperienceMap map(cfg);
  map.Load(BuildLaps(n));
  uint32_t current = 0;
  uint64_t frame = 0;
  for (auto _ : state) {
    map.Integrate(1.0, 0.02, 0.1);
    ExperienceAction a;
    a.from_experience_id = current;
    if (frame % 10 == 9) {
      a.kind = ExperienceAction::Kind::kLink;
      a.experience_id = (current + 37) % n;
    } else {
      a.kind = ExperienceAction::Kind::kSet;
      a.experience_id = (current + 1) % n;
    }
    a.sequence = frame++;
    map.Apply(a);
    current = a.experience_id;
  }
  state.counters["experiences"] = n;
  state.counters["links"] = static_cast<double>(map.links().size());
}

void BM_ExperienceMapFrameBudgeted(benchmark::State& state) { RunFrames(state, ExperienceMapConfig{}); }

void BM_ExperienceMapFrameFullRelaxation(benchmark::State& state) {
  ExperienceMapConfig cfg;
  cfg.exp_relax_budget_links = 0;  // OpenRatSLAM: exp_loops full sweeps after every action
  cfg.exp_loops = 10;
  RunFrames(state, cfg);
}

void BM_ExperienceMapFrameLeastSquares(benchmark::State& state) {
  ExperienceMapConfig cfg;
  cfg.exp_graph_optimisation = true;
  RunFrames(state, cfg);
}

void RunCorrection(benchmark::State& state, bool walls) {
  const pb::ExperienceMap laps = BuildLaps(static_cast<int>(state.range(0)), walls);
  ExperienceMapConfig cfg;
  cfg.exp_graph_optimisation = true;
  cfg.exp_manhattan = walls;
  cfg.exp_manhattan_sigma_rad = 0.05;
  ExperienceMap map(cfg);
  for (auto _ : state) {
    state.PauseTiming();
    map.Load(laps);  // from the same noisy start every time
    state.ResumeTiming();
    map.OptimiseGraph(cfg.exp_graph_iterations);
  }
  state.counters["experiences"] = static_cast<double>(map.experiences().size());
  state.counters["links"] = static_cast<double>(map.links().size());
}

void BM_ExperienceMapLeastSquaresCorrection(benchmark::State& state) { RunCorrection(state, false); }
void BM_ExperienceMapLeastSquaresCorrectionWithWalls(benchmark::State& state) { RunCorrection(state, true); }

// n points 3 cm apart along three walls of a room's corner: across 2 m ahead, 1 m to the left, and
// a box's face 1 m to the right; the same walls seen from (0.1, 0.05, 0.03).
void BM_RegisterScans(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::vector<Eigen::Vector2f> target, source;
  for (int i = 0; i < n; ++i) {
    const double t = 0.03 * (i / 3);
    const Eigen::Vector2f p = i % 3 == 0 ? Eigen::Vector2f(2.0f, static_cast<float>(-1.0 + std::fmod(t, 2.0)))
                              : i % 3 == 1 ? Eigen::Vector2f(static_cast<float>(std::fmod(t, 2.0)), 1.0f)
                                           : Eigen::Vector2f(static_cast<float>(0.5 + std::fmod(t, 1.0)), -1.0f);
    target.push_back(p);
    const rslam::Pose2D q = rslam::Between({0.1, 0.05, 0.03}, {p.x(), p.y(), 0.0});
    source.emplace_back(static_cast<float>(q.x), static_cast<float>(q.y));
  }
  for (auto _ : state) benchmark::DoNotOptimize(rslam::experience_map::RegisterScans(target, source, {}));
}

BENCHMARK(BM_RegisterScans)->Arg(100)->Arg(300)->Arg(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ExperienceMapFrameBudgeted)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ExperienceMapFrameFullRelaxation)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ExperienceMapFrameLeastSquares)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ExperienceMapLeastSquaresCorrection)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ExperienceMapLeastSquaresCorrectionWithWalls)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace
