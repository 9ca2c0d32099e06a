#include "tools/run/ratslam_config.h"

#include <array>
#include <cstdlib>
#include <string_view>

#include "common/config/config_error.h"
#include "common/config/config_loader.h"

namespace rslam::run {

namespace {

constexpr std::array<std::string_view, 4> kCoreSections = {"odometry", "templates", "pose_cells", "experience_map"};
constexpr std::array<std::string_view, 5> kOtherSections = {"bus", "service", "camera", "occupancy", "explorer"};

bool Contains(const auto& list, const std::string& name) {
  for (std::string_view s : list) {
    if (s == name) return true;
  }
  return false;
}

bool IsTrue(const YAML::Node& node) {
  try {
    return node && node.IsScalar() && node.as<bool>();
  } catch (const YAML::Exception&) {
    return false;
  }
}

bool IsNonZero(const YAML::Node& node) {
  try {
    return node && node.IsScalar() && node.as<double>() != 0.0;
  } catch (const YAML::Exception&) {
    return true;  // not a number: not a crop the runner can ignore
  }
}

// The camera service may change frames before anyone sees them (crop, anti-vignetting,
// undistortion); the runner reads frames as the camera's sources deliver them, so such a config
// would silently build a different map. Refused instead. (`grey` is fine: the stages convert
// exactly as the camera would.)
void CheckCameraPreparation(const YAML::Node& root) {
  if (!root || !root.IsMap() || !root["camera"] || !root["camera"].IsMap()) return;
  const YAML::Node camera = root["camera"];
  for (const char* key : {"anti_vignetting", "undistort"}) {
    if (IsTrue(camera[key])) {
      throw ConfigError(std::string("camera.") + key, "rslam run does not prepare frames; correct them beforehand");
    }
  }
  if (const YAML::Node crop = camera["crop"]; crop && crop.IsMap()) {
    for (const char* key : {"x", "y", "width", "height"}) {
      if (IsNonZero(crop[key])) {
        throw ConfigError(std::string("camera.crop.") + key, "rslam run does not crop frames; crop them beforehand");
      }
    }
  }
}

}  // namespace

RatSlamConfig RatSlamConfigFromYaml(const YAML::Node& root) {
  if (root && !root.IsNull()) {
    if (!root.IsMap()) throw ConfigError("<top level>", "expected a mapping of sections");
    for (const auto& kv : root) {
      const std::string section = kv.first.as<std::string>();
      if (!Contains(kCoreSections, section) && !Contains(kOtherSections, section)) {
        throw ConfigError(section, "unknown section (expected odometry, templates, pose_cells, experience_map)");
      }
    }
  }
  CheckCameraPreparation(root);
  RatSlamConfig config;
  const YAML::Node document = root ? root : YAML::Node(YAML::NodeType::Map);
  LoadConfigSection(document, "odometry", config.odometry);
  // The runner reads grey frames and replays the column-profile odometry only.
  if (config.odometry.floor.enabled)
    throw ConfigError("odometry.floor_odometry.enabled", "not supported by `rslam run` (run the services instead)");
  LoadConfigSection(document, "templates", config.templates);
  LoadConfigSection(document, "pose_cells", config.pose_cells);
  LoadConfigSection(document, "experience_map", config.experience_map);
  return config;
}

void MergeYaml(YAML::Node& base, const YAML::Node& overlay) {
  if (!overlay || overlay.IsNull()) return;
  if (!overlay.IsMap() || !base.IsMap()) {
    base = YAML::Clone(overlay);
    return;
  }
  for (const auto& kv : overlay) {
    const std::string key = kv.first.as<std::string>();
    YAML::Node child = base[key];
    if (child.IsDefined() && child.IsMap() && kv.second.IsMap()) {
      MergeYaml(child, kv.second);
    } else {
      base[key] = YAML::Clone(kv.second);
    }
  }
}

std::filesystem::path FindPreset(const std::string& name, const std::filesystem::path& fallback_dir) {
  if (name.empty() || name.find('/') != std::string::npos) {
    throw ConfigError("preset", "'" + name + "' is not a preset name (use --config FILE for a file)");
  }
  std::vector<std::filesystem::path> folders;
  if (const char* env = std::getenv("RSLAM_PRESET_DIR"); env && *env) folders.emplace_back(env);
  if (!fallback_dir.empty()) folders.push_back(fallback_dir);
  std::string tried;
  for (const auto& folder : folders) {
    const std::filesystem::path candidate = folder / (name + ".yaml");
    if (std::filesystem::is_regular_file(candidate)) return candidate;
    tried += (tried.empty() ? "" : ", ") + candidate.string();
  }
  throw ConfigError("preset", "no preset '" + name + "' (looked for " + (tried.empty() ? "nothing" : tried) + ")");
}

YAML::Node ComposeRunYaml(const std::filesystem::path& preset_file, const std::string& config_file,
                          const std::vector<std::string>& overrides) {
  YAML::Node root(YAML::NodeType::Map);
  if (!preset_file.empty()) MergeYaml(root, LoadYamlFile(preset_file.string()));
  if (!config_file.empty()) MergeYaml(root, LoadYamlFile(config_file));
  for (const std::string& assignment : overrides) ApplyOverride(root, assignment);
  return root;
}

}  // namespace rslam::run
