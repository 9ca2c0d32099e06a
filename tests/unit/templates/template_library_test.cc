// Pins TemplateLibrary's column and patch modes (paper 000 eq. 8, OpenRatSLAM local view),
// persistence and bad-input handling.
#include "services/templates/template_library.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "tests/unit/templates/test_images.h"

namespace rslam::templates {
namespace {

using testing::AddNoise;
using testing::RollColumns;
using testing::Texture;

constexpr double kDeg = std::numbers::pi / 180.0;

TemplateConfig StLucia() { return TemplateConfig{}; }  // the defaults are OpenRatSLAM's St Lucia values

// 600 crop columns -> 60 template columns: 10 image pixels per template column.
TemplateConfig TenPixelColumns() {
  TemplateConfig c;
  c.image_crop_x_min = 20;
  c.image_crop_x_max = 620;
  c.crop_fov_deg = 50.0;
  return c;
}

TEST(TemplateLibraryTest, FirstViewIsLearntWithInfiniteDifference) {
  TemplateLibrary library(StLucia());
  const ViewMatch m = library.MatchOrLearn(Texture(640, 480, 1));
  EXPECT_TRUE(m.is_new);
  EXPECT_EQ(m.template_id, 0u);
  EXPECT_TRUE(std::isinf(m.difference));
  EXPECT_EQ(library.size(), 1u);
}

TEST(TemplateLibraryTest, SameImageMatchesItsTemplate) {
  TemplateLibrary library(StLucia());
  const cv::Mat scene = Texture(640, 480, 2);
  library.Learn(Texture(640, 480, 3));
  const uint32_t id = library.Learn(scene);
  const ViewMatch m = library.MatchOrLearn(AddNoise(scene, 2.0, 9));
  EXPECT_FALSE(m.is_new);
  EXPECT_EQ(m.template_id, id);
  EXPECT_EQ(m.relative_angle_rad, 0.0);
  EXPECT_LT(m.difference, 0.01);
  EXPECT_EQ(library.size(), 2u);
}

TEST(TemplateLibraryTest, DifferentImageLearnsANewTemplateWithDenseIds) {
  TemplateLibrary library(StLucia());
  for (uint32_t i = 0; i < 5; ++i) {
    const ViewMatch m = library.MatchOrLearn(Texture(640, 480, 100 + i));
    EXPECT_TRUE(m.is_new);
    EXPECT_EQ(m.template_id, i);
    if (i > 0) {
      EXPECT_GT(m.difference, StLucia().match_threshold);
    }
  }
  EXPECT_EQ(library.Learn(Texture(640, 480, 100)), 5u);  // Learn always stores
  EXPECT_EQ(library.size(), 6u);
}

TEST(TemplateLibraryTest, ShiftedImageMatchesWithTheRelativeAngle) {
  const cv::Mat wide = Texture(740, 480, 4);
  const cv::Mat original = wide(cv::Rect(50, 0, 640, 480)).clone();
  for (int columns : {3, -2, 5}) {
    TemplateLibrary library(TenPixelColumns());
    library.Learn(original);
    // The scene moved right by `columns` template columns: the robot turned left.
    const cv::Mat turned = wide(cv::Rect(50 - 10 * columns, 0, 640, 480)).clone();
    const ViewMatch m = library.MatchOrLearn(turned);
    ASSERT_FALSE(m.is_new) << columns;
    EXPECT_NEAR(m.relative_angle_rad, columns * 50.0 / 60.0 * kDeg, 1e-9) << columns;
    EXPECT_LT(m.difference, 0.01);
  }
}

TEST(TemplateLibraryTest, PanoramicMatchingWrapsAround) {
  TemplateConfig c;
  c.image_crop_x_min = 0;
  c.image_crop_x_max = -1;
  c.image_crop_y_min = 0;
  c.image_crop_y_max = -1;
  c.panoramic = true;
  c.patch_normalisation = 2;
  c.normalisation = 0;
  c.match_threshold = 0.054;
  const cv::Mat panorama = Texture(600, 100, 5);  // 10 px per template column, 6 degrees each
  for (int columns : {0, 7, 25, 30, -20, 41}) {
    TemplateLibrary library(c);
    library.Learn(panorama);
    const ViewMatch m = library.MatchOrLearn(RollColumns(panorama, 10 * columns));
    ASSERT_FALSE(m.is_new) << columns;
    double expected = columns * 6.0 * kDeg;
    if (expected > std::numbers::pi) expected -= 2 * std::numbers::pi;
    EXPECT_NEAR(std::cos(m.relative_angle_rad - expected), 1.0, 1e-9) << columns << " got " << m.relative_angle_rad;
    EXPECT_GT(m.relative_angle_rad, -std::numbers::pi);
    EXPECT_LE(m.relative_angle_rad, std::numbers::pi);
    // Patch normalisation clamps at the template edges, so the rolled view differs a little there.
    EXPECT_LT(m.difference, 0.02);
  }
  // Without wrap-around a half-turn is a new place.
  TemplateConfig flat = c;
  flat.panoramic = false;
  TemplateLibrary library(flat);
  library.Learn(panorama);
  EXPECT_TRUE(library.MatchOrLearn(RollColumns(panorama, 300)).is_new);
}

TEST(TemplateLibraryTest, ColumnModeIsEq8OnAHandComputedArray) {
  TemplateConfig c;
  c.mode = "column";
  c.image_crop_x_min = 0;
  c.image_crop_x_max = -1;
  c.image_crop_y_min = 0;
  c.image_crop_y_max = -1;
  c.template_x_size = 8;
  c.normalisation = 0;
  c.shift_match = 2;
  c.crop_fov_deg = 40;  // 5 degrees per column
  TemplateLibrary library(c);
  const cv::Mat stored = (cv::Mat_<uint8_t>(1, 8) << 10, 20, 30, 40, 50, 60, 70, 80);
  library.Learn(stored);
  // Moved right by one column with a new value entering at the left: f(+1) = 0 over 7 columns.
  const cv::Mat moved = (cv::Mat_<uint8_t>(1, 8) << 200, 10, 20, 30, 40, 50, 60, 70);
  const ViewMatch m = library.MatchOrLearn(moved);
  EXPECT_FALSE(m.is_new);
  EXPECT_DOUBLE_EQ(m.difference, 0.0);
  EXPECT_NEAR(m.relative_angle_rad, 5.0 * kDeg, 1e-12);
  // Only the last value differs: f(0) = |90 - 80| / 255 / 8; shifting only makes it worse
  // (f(+1) = 10 / 255, f(-1) = 80 / 255 / 7, ...).
  const cv::Mat last = (cv::Mat_<uint8_t>(1, 8) << 10, 20, 30, 40, 50, 60, 70, 90);
  EXPECT_DOUBLE_EQ(library.Differences(last)[0], 10.0 / 255.0 / 8.0);
  const cv::Mat offset = (cv::Mat_<uint8_t>(1, 8) << 20, 30, 40, 50, 60, 70, 80, 90);
  // f(-1) compares moved[n] with stored[n + 1]: 20-20, 30-30, ... over 7 columns -> 0.
  EXPECT_DOUBLE_EQ(library.Differences(offset)[0], 0.0);
}

TEST(TemplateLibraryTest, EarlyExitAndPrefilterAgreeWithExhaustiveDifferences) {
  TemplateConfig c = StLucia();
  TemplateLibrary library(c);
  std::vector<cv::Mat> scenes;
  for (int i = 0; i < 40; ++i) scenes.push_back(Texture(640, 480, 1000 + i, 16));
  for (const cv::Mat& s : scenes) library.Learn(s);
  for (int i = 0; i < 40; i += 3) {
    const cv::Mat query = AddNoise(scenes[i], 4.0, 50 + i);
    const std::vector<double> all = library.Differences(query);
    const auto best = std::min_element(all.begin(), all.end()) - all.begin();
    const ViewMatch m = library.MatchOrLearn(query);
    ASSERT_FALSE(m.is_new);
    EXPECT_EQ(m.template_id, static_cast<uint32_t>(best));
    EXPECT_DOUBLE_EQ(m.difference, all[best]);
  }
}

TEST(TemplateLibraryTest, SaveAndLoadRoundTripsExactly) {
  for (const bool panoramic : {false, true}) {
    TemplateConfig c = StLucia();
    c.panoramic = panoramic;
    c.patch_normalisation = panoramic ? 2 : 0;
    TemplateLibrary library(c);
    for (int i = 0; i < 6; ++i) library.Learn(Texture(640, 480, 200 + i));
    const proto::TemplateLibraryState saved = library.ToProto();
    proto::TemplateLibraryState parsed;
    ASSERT_TRUE(parsed.ParseFromString(saved.SerializeAsString()));
    TemplateLibrary loaded = TemplateLibrary::FromProto(parsed, c);
    EXPECT_EQ(loaded.size(), 6u);
    EXPECT_EQ(loaded.ToProto().SerializeAsString(), saved.SerializeAsString());
    const cv::Mat query = AddNoise(Texture(640, 480, 203), 3.0, 1);
    EXPECT_EQ(loaded.Differences(query), library.Differences(query));
    const ViewMatch a = library.MatchOrLearn(query);
    const ViewMatch b = loaded.MatchOrLearn(query);
    EXPECT_EQ(a.template_id, b.template_id);
    EXPECT_EQ(a.relative_angle_rad, b.relative_angle_rad);
  }
}

TEST(TemplateLibraryTest, InconsistentStateIsRefused) {
  TemplateLibrary library(StLucia());
  for (int i = 0; i < 3; ++i) library.Learn(Texture(640, 480, 300 + i));
  const proto::TemplateLibraryState good = library.ToProto();

  auto refused = [](const proto::TemplateLibraryState& state, TemplateConfig config) {
    try {
      TemplateLibrary::FromProto(state, config);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  proto::TemplateLibraryState short_pixels = good;
  short_pixels.mutable_templates(1)->mutable_pixels()->pop_back();
  EXPECT_NE(refused(short_pixels, StLucia()).find("pixels"), std::string::npos);

  proto::TemplateLibraryState sparse_ids = good;
  sparse_ids.mutable_templates(2)->set_id(7);
  EXPECT_NE(refused(sparse_ids, StLucia()).find("id"), std::string::npos);

  proto::TemplateLibraryState stray_histogram = good;
  stray_histogram.mutable_templates(0)->add_histogram(1.0f);
  EXPECT_FALSE(refused(stray_histogram, StLucia()).empty());

  proto::TemplateLibraryState wrong_size = good;
  wrong_size.set_width(61);
  EXPECT_FALSE(refused(wrong_size, StLucia()).empty());

  TemplateConfig other_preprocessing = StLucia();
  other_preprocessing.normalisation = 0.5;
  EXPECT_NE(refused(good, other_preprocessing).find("made by"), std::string::npos);

  TemplateConfig other_mode = StLucia();
  other_mode.mode = "column";
  EXPECT_NE(refused(good, other_mode).find("mode"), std::string::npos);

  proto::TemplateLibraryState bad_version = good;
  bad_version.set_format_version(99);
  EXPECT_FALSE(refused(bad_version, StLucia()).empty());

  // The threshold is not part of the encoding: changing it keeps the templates usable.
  TemplateConfig looser = StLucia();
  looser.match_threshold = 0.1;
  EXPECT_TRUE(refused(good, looser).empty());
}

// Colour frames are converted crop only; matching must be that of the whole frame converted
// to grey first (as the services and `rslam run` do).
TEST(TemplateLibraryTest, ColourFramesMatchAsTheirGreyConversion) {
  cv::RNG rng(31);
  std::vector<cv::Mat> colour;
  for (int i = 0; i < 6; ++i) {
    cv::Mat coarse(50, 66, CV_8UC3);
    rng.fill(coarse, cv::RNG::UNIFORM, 0, 256);
    cv::Mat frame;
    cv::resize(coarse, frame, cv::Size(640, 480), 0, 0, cv::INTER_CUBIC);
    colour.push_back(frame);
  }
  auto grey = [](const cv::Mat& bgr) {
    cv::Mat g;
    cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
    return g;
  };
  TemplateLibrary from_colour(StLucia()), from_grey(StLucia());
  for (int i = 0; i < 4; ++i) {
    from_colour.Learn(colour[i]);
    from_grey.Learn(grey(colour[i]));
  }
  EXPECT_EQ(from_colour.ToProto().SerializeAsString(), from_grey.ToProto().SerializeAsString());
  cv::Mat bgra;
  cv::cvtColor(colour[2], bgra, cv::COLOR_BGR2BGRA);
  EXPECT_EQ(from_colour.Differences(bgra), from_grey.Differences(grey(colour[2])));
  for (int i = 0; i < 6; ++i) {
    const ViewMatch a = from_colour.MatchOrLearn(colour[i]);
    const ViewMatch b = from_grey.MatchOrLearn(grey(colour[i]));
    EXPECT_EQ(a.template_id, b.template_id) << i;
    EXPECT_EQ(a.is_new, b.is_new) << i;
    EXPECT_EQ(a.difference, b.difference) << i;
  }
}

TEST(TemplateLibraryTest, BadImagesAreRejectedWithAReason) {
  TemplateLibrary library(StLucia());
  EXPECT_THROW(library.MatchOrLearn(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(library.MatchOrLearn(cv::Mat(480, 640, CV_8UC2, cv::Scalar::all(9))), std::invalid_argument);
  EXPECT_THROW(library.MatchOrLearn(cv::Mat(480, 640, CV_16UC3, cv::Scalar::all(9))), std::invalid_argument);
  EXPECT_THROW(library.Learn(cv::Mat(480, 640, CV_32FC1, cv::Scalar(0))), std::invalid_argument);
  try {
    library.Differences(cv::Mat(200, 300, CV_8UC1, cv::Scalar(0)));  // smaller than the crop
    FAIL() << "accepted an image smaller than the crop";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("crop"), std::string::npos);
  }
  EXPECT_EQ(library.size(), 0u);
  // A uniform image is legal and does not divide by zero.
  const ViewMatch m = library.MatchOrLearn(cv::Mat(480, 640, CV_8UC1, cv::Scalar(0)));
  EXPECT_TRUE(m.is_new);
  EXPECT_TRUE(std::isfinite(library.Differences(cv::Mat(480, 640, CV_8UC1, cv::Scalar(0)))[0]));
}

TEST(TemplateLibraryTest, BadConfigIsRejectedNamingTheKey) {
  TemplateConfig c;
  c.mode = "sift";
  EXPECT_THROW(TemplateLibrary{c}, ConfigError);
  TemplateConfig shift;
  shift.shift_match = 30;  // 2 * 30 >= 60
  try {
    TemplateLibrary library(shift);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "shift_match");
  }
  TemplateConfig dead;
  dead.dead_zone_columns = {36};
  EXPECT_THROW(TemplateLibrary{dead}, ConfigError);
}

}  // namespace
}  // namespace rslam::templates
