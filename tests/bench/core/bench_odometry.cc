// Visual odometry per-frame cost on 640x480 frames with the St Lucia settings (OpenRatSLAM:
// about 80-90 us a frame on this machine class); argument 1: rotation_from_halves.
#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include <vector>

#include "services/odometry/visual_odometry.h"

namespace {

// A wide smooth random texture (deterministic seed) to pan across.
cv::Mat OdometryTexture(int width, int height, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat coarse(height / 8 + 2, width / 8 + 2, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 20, 235);
  cv::Mat fine;
  cv::resize(coarse, fine, cv::Size(width + 16, height + 16), 0, 0, cv::INTER_CUBIC);
  return fine(cv::Rect(8, 8, width, height)).clone();
}

void BM_VisualOdometryStLucia640x480(benchmark::State& state) {
  const cv::Mat world = OdometryTexture(640 + 200, 480, 42);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 16; ++i) frames.push_back(world(cv::Rect((i * 13) % 200, 0, 640, 480)).clone());
  rslam::odometry::VisualOdometryConfig config;
  config.rotation_from_halves = state.range(0) != 0;
  rslam::odometry::VisualOdometry vo(config);
  std::size_t i = 0;
  double sink = 0;
  for (auto _ : state) {
    const rslam::odometry::Velocity v = vo.Update(frames[i++ % frames.size()], 0.1);
    sink += v.vrot;
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(state.iterations());
  state.counters["us_per_frame"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * 1e-6, benchmark::Counter::kIsRate |
                                                                            benchmark::Counter::kInvert);
}
BENCHMARK(BM_VisualOdometryStLucia640x480)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
