#include "tools/sim/sim_config.h"

#include <gtest/gtest.h>

#include "common/config/config_loader.h"

namespace rslam::sim {
namespace {

TEST(SimConfigTest, DefaultsAreValid) { EXPECT_NO_THROW(SimConfig{}.Validate()); }

TEST(SimConfigTest, LoadsFromYamlAndNamesTheBadKey) {
  SimConfig config;
  LoadConfigSection(YAML::Load("sim: {camera: {width: 640, height: 480}, motion: {robot_radius_m: 0.2}}"), "sim",
                    config);
  EXPECT_EQ(config.camera.width, 640);
  EXPECT_EQ(config.motion.robot_radius_m, 0.2);
  SimConfig bad;
  try {
    LoadConfigSection(YAML::Load("sim: {camera: {tilt_rad: 2.0}}"), "sim", bad);
    FAIL() << "accepted a tilt of 2 rad";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "sim.camera.tilt_rad");
  }
  SimConfig same_colours;
  same_colours.scene.ceiling_bgr = same_colours.scene.floor_bgr;
  EXPECT_THROW(same_colours.Validate(), ConfigError);
}

}  // namespace
}  // namespace rslam::sim
