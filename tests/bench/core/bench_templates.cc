// Template matching cost per frame and per stored template, St Lucia settings (patch mode,
// 60x10 templates, shift 5, 640x480 frames). OpenRatSLAM: about 2 us per stored template.
#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include <vector>

#include "services/templates/template_library.h"

namespace {

cv::Mat TemplateTexture(int width, int height, uint64_t seed, int cell) {
  cv::RNG rng(seed);
  cv::Mat coarse(height / cell + 2, width / cell + 2, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 20, 235);
  cv::Mat fine;
  cv::resize(coarse, fine, cv::Size(width + 2 * cell, height + 2 * cell), 0, 0, cv::INTER_CUBIC);
  return fine(cv::Rect(cell, cell, width, height)).clone();
}

// Stored templates come from distinct synthetic places; the queries are noisy re-visits of
// some of them (so the search finds a real match, as on a loop closure) and unseen places.
void RunTemplateBenchmark(benchmark::State& state, rslam::templates::TemplateConfig config, int width, int height,
                          bool differences_only) {
  const int stored = static_cast<int>(state.range(0));
  rslam::templates::TemplateLibrary library(config);
  // Learning 10,000 full frames takes a while: learn from a pool of textures shifted in
  // brightness and position so every template differs.
  std::vector<cv::Mat> pool;
  for (int i = 0; i < 64; ++i) pool.push_back(TemplateTexture(width + 64, height, 7 + i, 8 + (i % 5) * 4));
  for (int i = 0; i < stored; ++i) {
    const cv::Mat& base = pool[i % pool.size()];
    cv::Mat view = base(cv::Rect((i / 64) % 64, 0, width, height)).clone();
    view += cv::Scalar((i / 4096) * 7);
    library.Learn(view);
  }
  std::vector<cv::Mat> queries;
  for (int q = 0; q < 8; ++q) {
    cv::Mat view = pool[(q * 5) % pool.size()](cv::Rect((q * 11) % 64, 0, width, height)).clone();
    cv::Mat noise(view.size(), CV_8UC1);
    cv::RNG rng(99 + q);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 6);
    view += noise;
    queries.push_back(view);
  }
  std::size_t i = 0;
  std::size_t learnt = 0;
  for (auto _ : state) {
    const cv::Mat& query = queries[i++ % queries.size()];
    if (differences_only) {
      benchmark::DoNotOptimize(library.Differences(query));
    } else {
      learnt += library.MatchOrLearn(query).is_new;
    }
  }
  state.counters["learnt"] = static_cast<double>(learnt);
  state.counters["us_per_frame"] = benchmark::Counter(static_cast<double>(state.iterations()) * 1e-6,
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["us_per_template"] = benchmark::Counter(static_cast<double>(state.iterations()) * stored * 1e-6,
                                                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_TemplateMatchPatchStLucia(benchmark::State& state) {
  RunTemplateBenchmark(state, rslam::templates::TemplateConfig{}, 640, 480, false);
}
BENCHMARK(BM_TemplateMatchPatchStLucia)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);

// Exhaustive: every template's exact difference (no prefilter, no cross-template early exit).
void BM_TemplateMatchPatchStLuciaAllDifferences(benchmark::State& state) {
  RunTemplateBenchmark(state, rslam::templates::TemplateConfig{}, 640, 480, true);
}
BENCHMARK(BM_TemplateMatchPatchStLuciaAllDifferences)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);

void BM_TemplateMatchPatchPanoramicOxford(benchmark::State& state) {
  rslam::templates::TemplateConfig c;
  c.image_crop_x_min = 0;
  c.image_crop_x_max = -1;
  c.image_crop_y_min = 0;
  c.image_crop_y_max = -1;
  c.panoramic = true;
  c.patch_normalisation = 2;
  c.normalisation = 0;
  c.match_threshold = 0.054;
  RunTemplateBenchmark(state, c, 720, 160, false);
}
BENCHMARK(BM_TemplateMatchPatchPanoramicOxford)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);

void BM_TemplateMatchHistogram(benchmark::State& state) {
  rslam::templates::TemplateConfig c;
  c.mode = "histogram";
  c.image_crop_x_min = 0;
  c.image_crop_x_max = -1;
  c.image_crop_y_min = 0;
  c.image_crop_y_max = -1;
  c.dead_zone_columns = {34, 35};
  RunTemplateBenchmark(state, c, 560, 52, false);
}
BENCHMARK(BM_TemplateMatchHistogram)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);

}  // namespace
