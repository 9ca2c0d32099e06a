#include "tools/launch/launch_profile.h"

#include <algorithm>
#include <filesystem>

#include "common/config/config_loader.h"

namespace rslam::launch {
namespace fs = std::filesystem;

namespace {

struct RestartFields {
  RestartPolicy& p;
  template <class V>
  void VisitFields(V& v) {
    v("backoff_initial_s", p.backoff_initial_s, "first restart delay");
    v("backoff_max_s", p.backoff_max_s, "longest restart delay");
    v("max_restarts", p.max_restarts, "restarts before giving up on a process");
  }
};

std::vector<std::string> StringList(const YAML::Node& node, const std::string& key) {
  if (!node) return {};
  if (!node.IsSequence()) throw ConfigError(key, "expected a list");
  std::vector<std::string> out;
  for (std::size_t i = 0; i < node.size(); ++i) {
    if (!node[i].IsScalar()) throw ConfigError(key + "[" + std::to_string(i) + "]", "expected a string");
    out.push_back(node[i].as<std::string>());
  }
  return out;
}

}  // namespace

LaunchProfile LoadLaunchProfile(const std::string& name_or_path, const std::string& launch_dir) {
  LaunchProfile profile;
  profile.path = fs::exists(name_or_path) ? name_or_path : (fs::path(launch_dir) / (name_or_path + ".yaml")).string();
  if (!fs::exists(profile.path))
    throw ConfigError(name_or_path, "no such launch profile (looked for " + profile.path + ")");
  const YAML::Node root = LoadYamlFile(profile.path);
  const std::string file = profile.path + ": ";
  if (!root.IsMap()) throw ConfigError(file + "<top level>", "expected a mapping");
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>();
    if (key != "config" && key != "restart" && key != "processes") throw ConfigError(file + key, "unknown key");
  }
  if (root["config"]) {
    const fs::path c = root["config"].as<std::string>();
    profile.config = (c.is_absolute() ? c : fs::path(profile.path).parent_path() / c).lexically_normal().string();
    if (!fs::exists(profile.config)) throw ConfigError(file + "config", "no such file " + profile.config);
  }
  if (root["restart"]) {
    RestartFields fields{profile.restart};
    config_detail::DecodeMap(root["restart"], "restart.", fields);
  }
  const YAML::Node processes = root["processes"];
  if (!processes || !processes.IsSequence() || processes.size() == 0)
    throw ConfigError(file + "processes", "expected a non-empty list");
  for (std::size_t i = 0; i < processes.size(); ++i) {
    const std::string at = file + "processes[" + std::to_string(i) + "]";
    const YAML::Node p = processes[i];
    if (!p.IsMap() || !p["name"]) throw ConfigError(at, "expected a mapping with a name");
    LaunchEntry e;
    for (const auto& kv : p) {
      const auto key = kv.first.as<std::string>();
      if (key != "name" && key != "command" && key != "args" && key != "dds")
        throw ConfigError(at + "." + key, "unknown key");
    }
    e.name = p["name"].as<std::string>();
    e.command = StringList(p["command"], at + ".command");
    e.args = StringList(p["args"], at + ".args");
    if (p["dds"]) {
      e.dds = p["dds"].as<std::string>();
      if (e.dds != "cyclone" && e.dds != "fastdds") throw ConfigError(at + ".dds", "cyclone or fastdds");
    }
    profile.processes.push_back(std::move(e));
  }
  return profile;
}

std::string ServiceBinary(const std::string& bin_dir, const std::string& service) {
  std::string name = service;
  std::replace(name.begin(), name.end(), '_', '-');
  return (fs::path(bin_dir) / ("rslam-" + name)).string();
}

std::vector<ProcessSpec> BuildProcessSpecs(const LaunchProfile& profile, const LaunchOptions& options) {
  std::vector<ProcessSpec> specs;
  const std::string config = options.config.empty() ? profile.config : options.config;
  for (const auto& e : profile.processes) {
    ProcessSpec spec;
    spec.name = e.name;
    if (e.command.empty()) {
      spec.executable = ServiceBinary(options.bin_dir, e.name);
    } else {
      spec.executable = e.command[0] == "rslam" ? (fs::path(options.bin_dir) / "rslam").string() : e.command[0];
      spec.args.assign(e.command.begin() + 1, e.command.end());
    }
    const bool service = e.command.empty();
    if (service && !config.empty()) spec.args.insert(spec.args.end(), {"--config", config});
    if (!options.robot.empty() && service) spec.args.insert(spec.args.end(), {"--robot", options.robot});
    const std::string dds = e.dds.empty() ? options.dds : e.dds;
    if (!dds.empty()) spec.env["RSLAM_DDS"] = dds;
    if (options.domain >= 0) spec.env["RSLAM_DOMAIN"] = std::to_string(options.domain);
    if (service && !options.state_dir.empty()) spec.args.insert(spec.args.end(), {"--state-dir", options.state_dir});
    spec.args.insert(spec.args.end(), e.args.begin(), e.args.end());
    if (service) spec.args.insert(spec.args.end(), options.extra_args.begin(), options.extra_args.end());
    if (!options.log_dir.empty()) spec.log_file = (fs::path(options.log_dir) / (e.name + ".log")).string();
    specs.push_back(std::move(spec));
  }
  return specs;
}

}  // namespace rslam::launch
