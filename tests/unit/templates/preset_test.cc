// Every preset in deploy/presets loads and validates for the odometry and templates sections.
#include <gtest/gtest.h>

#include <string>

#include "common/config/config_loader.h"
#include "services/odometry/odometry_node_config.h"
#include "services/odometry/visual_odometry.h"
#include "services/templates/template_library.h"
#include "services/templates/templates_node_config.h"

namespace rslam {
namespace {

class PresetTest : public ::testing::TestWithParam<std::string> {};

TEST_P(PresetTest, OdometryAndTemplatesSectionsValidate) {
  const std::string path = std::string(RSLAM_SOURCE_DIR) + "/deploy/presets/" + GetParam() + ".yaml";
  const YAML::Node root = LoadYamlFile(path);
  ASSERT_TRUE(root["odometry"]) << path;
  ASSERT_TRUE(root["templates"]) << path;
  // A preset section is a service's config: the library's keys plus the service's own.
  odometry::OdometryNodeConfig odometry_config;
  templates::TemplatesNodeConfig template_config;
  EXPECT_NO_THROW(LoadConfigSection(root, "odometry", odometry_config));
  EXPECT_NO_THROW(LoadConfigSection(root, "templates", template_config));
  EXPECT_NO_THROW(odometry::VisualOdometry{odometry_config.visual});
  EXPECT_NO_THROW(templates::TemplateLibrary{template_config.library});
}

INSTANTIATE_TEST_SUITE_P(Presets, PresetTest, ::testing::Values("stlucia", "irat", "oxford", "nordland"));

TEST(PresetFileTest, StLuciaPresetHoldsOpenRatSlamValues) {
  const YAML::Node root = LoadYamlFile(std::string(RSLAM_SOURCE_DIR) + "/deploy/presets/stlucia.yaml");
  templates::TemplateConfig t;
  LoadConfigSection(root, "templates", t);
  EXPECT_EQ(t.image_crop_x_min, 40);
  EXPECT_EQ(t.image_crop_x_max, 600);
  EXPECT_EQ(t.template_x_size, 60);
  EXPECT_EQ(t.template_y_size, 10);
  EXPECT_DOUBLE_EQ(t.match_threshold, 0.085);
  odometry::OdometryNodeConfig o;
  LoadConfigSection(root, "odometry", o);
  EXPECT_EQ(o.visual.vrot_image_y_min, 75);
  EXPECT_DOUBLE_EQ(o.visual.vtrans_scaling, 1000);
}

TEST(PresetFileTest, UnknownKeyIsAnErrorNamingIt) {
  YAML::Node root = YAML::Load("templates:\n  vt_match_threshold: 0.1\n");
  templates::TemplateConfig t;
  try {
    LoadConfigSection(root, "templates", t);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "templates.vt_match_threshold");
  }
}

}  // namespace
}  // namespace rslam
