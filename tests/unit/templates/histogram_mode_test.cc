// Pins histogram mode to paper 001: Jeffrey divergence (eq. 1) and orientation recovery over
// 36 rotations with the camera's dead zone masked.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "services/templates/jeffrey_divergence.h"
#include "services/templates/template_library.h"
#include "tests/unit/templates/test_images.h"

namespace rslam::templates {
namespace {

using testing::RollColumns;
using testing::Texture;

TEST(HistogramModeTest, JeffreyDivergenceMatchesHandComputedEq1) {
  const std::vector<float> h = {0.5f, 0.5f, 0.0f};
  const std::vector<float> k = {0.25f, 0.25f, 0.5f};
  // Bins 0 and 1: 0.5 ln(1 / 0.75) + 0.25 ln(0.5 / 0.75); bin 2: 0 + 0.5 ln(2).
  const double expected = 2 * (0.5 * std::log(1.0 / 0.75) + 0.25 * std::log(0.5 / 0.75)) + 0.5 * std::log(2.0);
  EXPECT_NEAR(JeffreyDivergence(h, k), expected, 1e-7);
  EXPECT_NEAR(JeffreyDivergence(h, k), 0.431523, 1e-6);
  EXPECT_NEAR(JeffreyDivergence(k, h), expected, 1e-7);  // symmetric
  EXPECT_DOUBLE_EQ(JeffreyDivergence(h, h), 0.0);
  // Disjoint normalised histograms reach the maximum 2 ln 2.
  const std::vector<float> a = {1, 0}, b = {0, 1};
  EXPECT_NEAR(JeffreyDivergence(a, b), 2 * std::log(2.0), 1e-12);
  // The split form the library uses gives the same value.
  EXPECT_NEAR(JeffreyDivergenceFromSelfTerms(h, JeffreySelfTerm(h), k, JeffreySelfTerm(k)), expected, 1e-6);
  const std::vector<float> nan = {std::numeric_limits<float>::quiet_NaN(), 1.0f, 0.0f};
  EXPECT_THROW(JeffreyDivergence(nan, k), std::invalid_argument);
  EXPECT_THROW(JeffreyDivergence(a, k), std::invalid_argument);
}

TemplateConfig Panorama() {
  TemplateConfig c;
  c.mode = "histogram";
  c.image_crop_x_min = 0;
  c.image_crop_x_max = -1;
  c.image_crop_y_min = 0;
  c.image_crop_y_max = -1;
  c.dead_zone_columns = {33, 34, 35};  // 30 degrees of mirror support behind the robot
  c.histogram_divergence_threshold = 0.1;
  return c;
}

// A 360-column panorama (1 degree per column, 10 per rotation step) whose dead zone, fixed to
// the camera, is painted flat.
cv::Mat WithDeadZone(cv::Mat panorama) {
  panorama(cv::Rect(330, 0, 30, panorama.rows)).setTo(cv::Scalar(128));
  return panorama;
}

TEST(HistogramModeTest, RecoversEachOf36RotationsWithTheDeadZoneMasked) {
  const cv::Mat world = Texture(360, 56, 11, 6);
  TemplateLibrary library(Panorama());
  library.Learn(WithDeadZone(world.clone()));
  for (int r = 0; r < 36; ++r) {
    // The robot turned left by r steps: the world moves right by 10 r columns in the panorama.
    const ViewMatch m = library.MatchOrLearn(WithDeadZone(RollColumns(world, 10 * r)));
    ASSERT_FALSE(m.is_new) << "rotation " << r << " divergence " << m.difference;
    double expected = r * 10.0 * std::numbers::pi / 180.0;
    if (expected > std::numbers::pi) expected -= 2 * std::numbers::pi;
    EXPECT_NEAR(m.relative_angle_rad, expected, 1e-9) << "rotation " << r;
    const int index = static_cast<int>(std::lround(m.relative_angle_rad / (10.0 * std::numbers::pi / 180.0)) + 36) % 36;
    EXPECT_EQ(index, r);
  }
  EXPECT_EQ(library.size(), 1u);
}

TEST(HistogramModeTest, PicksTheRightPlaceAmongSeveral) {
  TemplateLibrary library(Panorama());
  std::vector<cv::Mat> worlds;
  for (int i = 0; i < 6; ++i) {
    worlds.push_back(Texture(360, 56, 40 + i, 6 + i));
    library.Learn(WithDeadZone(worlds.back().clone()));
  }
  for (int i = 0; i < 6; ++i) {
    const ViewMatch m = library.MatchOrLearn(WithDeadZone(RollColumns(worlds[i], 70)));
    ASSERT_FALSE(m.is_new);
    EXPECT_EQ(m.template_id, static_cast<uint32_t>(i));
    EXPECT_NEAR(m.relative_angle_rad, 70.0 * std::numbers::pi / 180.0, 1e-9);
  }
}

TEST(HistogramModeTest, NewHistogramAboveTheDivergenceThresholdIsLearnt) {
  TemplateConfig c = Panorama();
  c.histogram_divergence_threshold = 0.0103;
  c.histogram_normalise_intensity = false;
  TemplateLibrary library(c);
  const cv::Mat dark = Texture(360, 56, 12) / 3;
  const cv::Mat bright = dark + 150;
  library.Learn(dark);
  const ViewMatch m = library.MatchOrLearn(bright);
  EXPECT_TRUE(m.is_new);
  EXPECT_EQ(m.template_id, 1u);
  EXPECT_GT(m.difference, c.histogram_divergence_threshold);
  const std::vector<double> d = library.Differences(dark);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_NEAR(d[0], 0.0, 1e-6);  // float logs
  EXPECT_NEAR(d[1], m.difference, 1e-6);
}

TEST(HistogramModeTest, RoundTripsHistogramsAndRefusesABadOne) {
  TemplateLibrary library(Panorama());
  for (int i = 0; i < 3; ++i) library.Learn(Texture(360, 56, 60 + i));
  const proto::TemplateLibraryState state = library.ToProto();
  TemplateLibrary loaded = TemplateLibrary::FromProto(state, Panorama());
  EXPECT_EQ(loaded.ToProto().SerializeAsString(), state.SerializeAsString());
  const cv::Mat query = Texture(360, 56, 61);
  EXPECT_EQ(loaded.Differences(query), library.Differences(query));

  proto::TemplateLibraryState bad = state;
  bad.mutable_templates(1)->set_histogram(0, 5.0f);  // no longer sums to 1
  EXPECT_THROW(TemplateLibrary::FromProto(bad, Panorama()), std::invalid_argument);
  proto::TemplateLibraryState missing = state;
  missing.mutable_templates(0)->mutable_histogram()->RemoveLast();
  EXPECT_THROW(TemplateLibrary::FromProto(missing, Panorama()), std::invalid_argument);
  TemplateConfig other_dead_zone = Panorama();
  other_dead_zone.dead_zone_columns = {0};
  EXPECT_THROW(TemplateLibrary::FromProto(state, other_dead_zone), std::invalid_argument);
}

// The library skips histograms by this bound, so it must never exceed the divergence.
TEST(HistogramModeTest, JeffreyLowerBoundNeverExceedsTheDivergence) {
  cv::RNG rng(2024);
  auto normalised = [](std::vector<float> v) {
    double total = 0;
    for (float x : v) total += x;
    for (float& x : v) x = static_cast<float>(x / total);
    return v;
  };
  int informative = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const int bins = 1 + trial % 64;
    std::vector<float> h(bins), k(bins);
    const int kind = trial % 3;  // unrelated, near-identical, sparse
    for (int b = 0; b < bins; ++b) {
      h[b] = kind == 2 && rng.uniform(0, 3) != 0 ? 0.0f : static_cast<float>(rng.uniform(0.0, 1.0));
      k[b] = kind == 1 ? h[b] * static_cast<float>(rng.uniform(0.95, 1.05))
                       : (kind == 2 && rng.uniform(0, 3) != 0 ? 0.0f : static_cast<float>(rng.uniform(0.0, 1.0)));
    }
    h[0] += 1e-3f;  // never all zero
    k[bins - 1] += 1e-3f;
    h = normalised(h);
    k = normalised(k);
    const double bound = JeffreyDivergenceLowerBound(h, k);
    const double computed = JeffreyDivergenceFromSelfTerms(h, JeffreySelfTerm(h), k, JeffreySelfTerm(k));
    ASSERT_LE(bound, computed) << "trial " << trial;
    ASSERT_LE(bound, JeffreyDivergence(h, k)) << "trial " << trial;
    informative += bound > 0.0;
  }
  EXPECT_GT(informative, 1000) << "the bound must be useful, not just 0";
  // Disjoint histograms: d_J = 2 ln 2, the bound sum (h - k)^2 / (2 (h + k)) = 1 (less the margin).
  const std::vector<float> a = {1, 0}, b = {0, 1};
  EXPECT_NEAR(JeffreyDivergenceLowerBound(a, b), 0.999 - 1e-5, 1e-7);
  // Bins empty in both count nothing; equal histograms give no bound.
  const std::vector<float> c = {0.5f, 0, 0.5f}, d = {0.25f, 0, 0.75f};
  EXPECT_LE(JeffreyDivergenceLowerBound(c, d), JeffreyDivergence(c, d));
  EXPECT_GT(JeffreyDivergenceLowerBound(c, d), 0.9 * JeffreyDivergence(c, d)) << "tight for similar histograms";
  EXPECT_EQ(JeffreyDivergenceLowerBound(c, c), 0.0);
}

// Matching skips histograms whose bound rules them out; what it reports must be what every
// divergence computed (Differences(), exhaustive) gives: the smallest divergence for a new view;
// for a familiar one, a template among the histogram_max_candidates lowest (divergence, id)
// within the threshold (the lowest itself when only one is refined), with its own divergence.
TEST(HistogramModeTest, SkippingHistogramsKeepsTheSmallestDivergenceAndTheCandidates) {
  for (const int max_candidates : {1, 3, 8}) {
    TemplateConfig c = Panorama();
    c.histogram_divergence_threshold = 0.02;
    c.histogram_normalise_intensity = false;  // unseen places differ in brightness too
    c.histogram_max_candidates = max_candidates;
    TemplateLibrary library(c);
    // Each place learnt four times with a little noise: several close candidates per view.
    cv::RNG rng(31);
    auto noisy = [&](const cv::Mat& image) {
      cv::Mat noise(image.size(), CV_8UC1);
      rng.fill(noise, cv::RNG::UNIFORM, 0, 12);
      return cv::Mat(image + noise);
    };
    std::vector<cv::Mat> worlds;
    for (int i = 0; i < 30; ++i) {
      worlds.push_back(Texture(360, 56, 300 + i, 4 + i % 9));
      for (int copy = 0; copy < 4; ++copy) library.Learn(WithDeadZone(noisy(worlds.back())));
    }
    int matched = 0, learnt = 0;
    for (int q = 0; q < 40; ++q) {
      cv::Mat query = q % 2 == 0 ? noisy(RollColumns(worlds[(q * 7) % worlds.size()], 10 * q))
                                 : cv::Mat(Texture(360, 56, 5000 + q, 4 + q % 9) / 2 + 2 * q);
      query = WithDeadZone(query);
      const std::vector<double> all = library.Differences(query);  // before a new view is learnt
      std::vector<std::pair<double, uint32_t>> within;
      for (uint32_t id = 0; id < all.size(); ++id) {
        if (all[id] <= c.histogram_divergence_threshold) within.emplace_back(all[id], id);
      }
      std::sort(within.begin(), within.end());
      within.resize(std::min<std::size_t>(within.size(), max_candidates));
      const ViewMatch m = library.MatchOrLearn(query);
      if (m.is_new) {
        ++learnt;
        EXPECT_EQ(m.difference, *std::min_element(all.begin(), all.end())) << "query " << q;
      } else {
        ++matched;
        ASSERT_LT(m.template_id, all.size());
        EXPECT_EQ(m.difference, all[m.template_id]) << "query " << q;
        EXPECT_TRUE(std::find(within.begin(), within.end(), std::make_pair(m.difference, m.template_id)) !=
                    within.end())
            << "query " << q << ": template " << m.template_id << " is not among the lowest " << max_candidates;
        if (max_candidates == 1) {
          EXPECT_EQ(m.template_id, within.front().second);
        }
      }
    }
    EXPECT_GT(matched, 0);
    EXPECT_GT(learnt, 0);
  }
}

}  // namespace
}  // namespace rslam::templates
