#include "common/node/service_main.h"

#include <set>

namespace rslam {

bool IsKnownConfigSection(const std::string& name) {
  static const std::set<std::string> kSections = {"bus",       "service",        "camera",    "odometry",
                                                  "templates", "pose_cells",     "experience_map",
                                                  "occupancy", "explorer",       "sim"};
  return kSections.count(name) > 0;
}

void AddServiceFlags(CLI::App& app, ServiceCommandLine& cl) {
  app.add_option("--config", cl.config_file, "YAML config file")->check(CLI::ExistingFile);
  app.add_option("--robot", cl.robot, "robot id (bus.robot_id)");
  app.add_option("--dds", cl.dds, "DDS vendor: cyclone or fastdds (bus.dds; env RSLAM_DDS)")
      ->check(CLI::IsMember({"cyclone", "fastdds"}));
  app.add_option("--domain", cl.domain, "DDS domain id (bus.domain_id; env RSLAM_DOMAIN)")->check(CLI::Range(0, 229));
  app.add_option("--set", cl.overrides, "override a config key: section.key=value (repeatable)");
  app.add_option("--state-dir", cl.state_dir, "folder for state files (service.state_dir)");
  app.add_flag("--fresh", cl.fresh, "ignore saved state (service.fresh)");
  app.add_option("--log-level", cl.log_level, "trace, debug, info, warn, error, off");
}

YAML::Node LoadServiceYaml(const ServiceCommandLine& cl) {
  YAML::Node root = cl.config_file.empty() ? YAML::Node(YAML::NodeType::Map) : LoadYamlFile(cl.config_file);
  if (root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  if (!root.IsMap()) throw ConfigError(cl.config_file, "expected a mapping of sections");
  for (const auto& o : cl.overrides) ApplyOverride(root, o);
  for (const auto& kv : root) {
    const std::string section = kv.first.as<std::string>();
    if (!IsKnownConfigSection(section)) throw ConfigError(section, "unknown config section");
  }
  return root;
}

bus::BusConfig ResolveBusConfig(const YAML::Node& root, const ServiceCommandLine& cl) {
  bus::BusConfig config;
  LoadConfigSection(root, "bus", config);
  config.ApplyEnvironment();
  if (!cl.robot.empty()) config.robot_id = cl.robot;
  if (!cl.dds.empty()) config.dds = cl.dds;
  if (cl.domain >= 0) config.domain_id = cl.domain;
  ValidateConfig(config, "bus");
  return config;
}

ServiceRuntimeConfig ResolveRuntimeConfig(const YAML::Node& root, const ServiceCommandLine& cl) {
  ServiceRuntimeConfig config;
  LoadConfigSection(root, "service", config);
  if (!cl.state_dir.empty()) config.state_dir = cl.state_dir;
  if (cl.fresh) config.fresh = true;
  if (!cl.log_level.empty()) config.log_level = cl.log_level;
  return config;
}

}  // namespace rslam
