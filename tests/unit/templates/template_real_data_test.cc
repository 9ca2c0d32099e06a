// Real data: Nordland summer/winter (place recognition across seasons) and iRat frames.
// Skipped when RSLAM_SHARED_DATA is absent.
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "common/config/config_loader.h"
#include "services/odometry/visual_odometry.h"
#include "services/templates/template_library.h"

namespace rslam::templates {
namespace {

std::filesystem::path SharedData(const std::string& sub) {
  const char* root = std::getenv("RSLAM_SHARED_DATA");
  if (!root) return {};
  const std::filesystem::path p = std::filesystem::path(root) / sub;
  return std::filesystem::exists(p) ? p : std::filesystem::path();
}

template <class Config>
Config FromPreset(const std::string& preset, const std::string& section) {
  Config config;
  LoadConfigSection(LoadYamlFile(std::string(RSLAM_SOURCE_DIR) + "/deploy/presets/" + preset + ".yaml"), section,
                    config);
  return config;
}

TEST(TemplateRealDataTest, RecognisesNordlandPlacesAfterSeasonChange) {
  const std::filesystem::path nordland = SharedData("nordland");
  if (nordland.empty()) GTEST_SKIP() << "RSLAM_SHARED_DATA/nordland absent";
  TemplateLibrary library(FromPreset<TemplateConfig>("nordland", "templates"));
  std::vector<cv::Mat> winter;
  for (int frame = 10; frame <= 20000; frame += 100) {  // 200 places, 100 s of travel apart
    char name[32];
    std::snprintf(name, sizeof name, "images-%05d.png", frame);
    const cv::Mat summer = cv::imread((nordland / "summer" / name).string(), cv::IMREAD_GRAYSCALE);
    winter.push_back(cv::imread((nordland / "winter" / name).string(), cv::IMREAD_GRAYSCALE));
    ASSERT_FALSE(summer.empty() || winter.back().empty()) << name;
    library.Learn(summer);
  }
  int recognised = 0;
  for (std::size_t place = 0; place < winter.size(); ++place) {
    const std::vector<double> d = library.Differences(winter[place]);
    recognised += static_cast<std::size_t>(std::min_element(d.begin(), d.end()) - d.begin()) == place;
  }
  const double share = static_cast<double>(recognised) / winter.size();
  RecordProperty("recall_at_1", std::to_string(share));
  std::printf("Nordland winter -> summer recall@1: %.3f (%d of %zu; chance %.3f)\n", share, recognised, winter.size(),
              1.0 / winter.size());
  // Chance is 0.005; the preset was tuned to about 0.5 on this set.
  EXPECT_GE(share, 0.35);
}

TEST(TemplateRealDataTest, IratFramesRunThroughOdometryAndTemplates) {
  const std::filesystem::path irat = SharedData("irat");
  if (irat.empty()) GTEST_SKIP() << "RSLAM_SHARED_DATA/irat absent";
  odometry::VisualOdometry vo(FromPreset<odometry::VisualOdometryConfig>("irat", "odometry"));
  TemplateLibrary library(FromPreset<TemplateConfig>("irat", "templates"));
  const std::vector<std::string> runs = {"test_A_batch_0000", "test_B_batch_0000"};
  const std::vector<std::vector<int>> frames = {{33, 34, 35, 36, 37}, {0, 1, 2, 3, 4}};
  int seen = 0;
  for (std::size_t run = 0; run < runs.size(); ++run) {
    vo.Reset();
    for (int frame : frames[run]) {
      char suffix[8];
      std::snprintf(suffix, sizeof suffix, "%02d", frame);
      const cv::Mat grey = cv::imread((irat / (runs[run] + suffix + ".png")).string(), cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(grey.empty()) << runs[run] << suffix;
      const odometry::Velocity v = vo.Update(grey, 0.1);
      EXPECT_TRUE(std::isfinite(v.vtrans) && std::isfinite(v.vrot));
      const ViewMatch m = library.MatchOrLearn(grey);
      EXPECT_LT(m.template_id, library.size());
      // Seeing the same frame again right away is recognised as that template.
      const ViewMatch again = library.MatchOrLearn(grey);
      EXPECT_FALSE(again.is_new);
      EXPECT_EQ(again.template_id, m.template_id);
      ++seen;
    }
  }
  EXPECT_EQ(seen, 10);
  EXPECT_GE(library.size(), 2u);  // two different runs are not one view
}

}  // namespace
}  // namespace rslam::templates
