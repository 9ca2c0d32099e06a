// The config loader names the bad key; the bus config validates vendor, domain and robot.

#include <gtest/gtest.h>

#include <cstdlib>

#include "common/bus/bus_config.h"
#include "common/config/config_loader.h"

namespace rslam {
namespace {

struct InnerConfig {
  double gain = 1.0;
  std::vector<int> sizes = {1, 2};
  template <class V>
  void VisitFields(V& v) {
    v("gain", gain, "multiplies the input");
    v("sizes", sizes, "some sizes");
  }
  void Validate() const { Require(gain > 0, "gain", "must be positive"); }
};

struct OuterConfig {
  int count = 3;
  bool enabled = false;
  std::string name = "x";
  InnerConfig inner;
  template <class V>
  void VisitFields(V& v) {
    v("count", count, "how many");
    v("enabled", enabled, "on or off");
    v("name", name, "a name");
    v("inner", inner, "nested");
  }
  void Validate() const {
    Require(count >= 0, "count", "must not be negative");
    inner.Validate();
  }
};

std::string ErrorKey(const std::string& yaml) {
  OuterConfig cfg;
  try {
    LoadConfigSection(YAML::Load(yaml), "svc", cfg);
  } catch (const ConfigError& e) {
    return e.key();
  }
  return "";
}

TEST(ConfigLoaderTest, FillsFieldsOverDefaults) {
  OuterConfig cfg;
  LoadConfigSection(YAML::Load("svc: {count: 5, inner: {gain: 2.5, sizes: [4]}}"), "svc", cfg);
  EXPECT_EQ(cfg.count, 5);
  EXPECT_EQ(cfg.name, "x");
  EXPECT_DOUBLE_EQ(cfg.inner.gain, 2.5);
  EXPECT_EQ(cfg.inner.sizes, std::vector<int>{4});
}

TEST(ConfigLoaderTest, UnknownKeysAreNamed) {
  EXPECT_EQ(ErrorKey("svc: {cuont: 5}"), "svc.cuont");
  EXPECT_EQ(ErrorKey("svc: {inner: {gian: 1}}"), "svc.inner.gian");
}

TEST(ConfigLoaderTest, WrongTypesAreNamed) {
  EXPECT_EQ(ErrorKey("svc: {count: many}"), "svc.count");
  EXPECT_EQ(ErrorKey("svc: {enabled: perhaps}"), "svc.enabled");
  EXPECT_EQ(ErrorKey("svc: {inner: {sizes: 3}}"), "svc.inner.sizes");
  EXPECT_EQ(ErrorKey("svc: {inner: {sizes: [1, x]}}"), "svc.inner.sizes[1]");
  EXPECT_EQ(ErrorKey("svc: [1, 2]"), "svc");
}

TEST(ConfigLoaderTest, BadValuesAreNamedByValidation) {
  EXPECT_EQ(ErrorKey("svc: {count: -1}"), "svc.count");
  EXPECT_EQ(ErrorKey("svc: {inner: {gain: 0}}"), "svc.gain");
}

TEST(ConfigLoaderTest, OverridesAndHelpUseTheSameKeys) {
  YAML::Node root = YAML::Load("svc: {count: 1}");
  ApplyOverride(root, "svc.inner.gain=4");
  OuterConfig cfg;
  LoadConfigSection(root, "svc", cfg);
  EXPECT_DOUBLE_EQ(cfg.inner.gain, 4.0);
  const std::string help = DescribeConfig(cfg, "svc");
  EXPECT_NE(help.find("svc.inner.gain = 4"), std::string::npos) << help;
  EXPECT_NE(help.find("multiplies the input"), std::string::npos);
  EXPECT_THROW(ApplyOverride(root, "novalue"), ConfigError);
}

TEST(ConfigLoaderTest, MissingOrMalformedFilesAreNamed) {
  EXPECT_THROW(LoadYamlFile("/nonexistent/rslam.yaml"), ConfigError);
}

TEST(BusConfigTest, RejectsUnknownVendorAndBadDomain) {
  bus::BusConfig cfg;
  cfg.dds = "opendds";
  try {
    cfg.Validate();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.key(), "dds");
  }
  cfg.dds = "fastdds";
  cfg.domain_id = 300;
  EXPECT_THROW(cfg.Validate(), ConfigError);
  cfg.domain_id = 3;
  cfg.robot_id = "robot*";
  EXPECT_THROW(cfg.Validate(), ConfigError);
}

TEST(BusConfigTest, EnvironmentSelectsTheVendor) {
  bus::BusConfig cfg;
  setenv("RSLAM_DDS", "fastdds", 1);
  cfg.ApplyEnvironment();
  EXPECT_EQ(cfg.vendor(), bus::Vendor::kFastDds);
  setenv("RSLAM_DDS", "bogus", 1);
  EXPECT_THROW(cfg.ApplyEnvironment(), ConfigError);
  unsetenv("RSLAM_DDS");
}

}  // namespace
}  // namespace rslam
