#pragma once
// The configuration of the whole RatSLAM core as one YAML document: the sections the four
// services read (odometry, templates, pose_cells, experience_map), filled into the services' own
// node config structs, so a preset or service config file means the same to `rslam run` as to
// the distributed services (same keys, same defaults, same validation). The runner uses the
// algorithm keys and the node keys that change what reaches the algorithms
// (odometry.max_frame_gap_s, pose_cells.max_dt_s / max_vtrans_mps / max_vrot_radps,
// experience_map.max_dt_s); transport and persistence keys are accepted and have no effect.

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>
#include <vector>

#include "services/experience_map/experience_map_node_config.h"
#include "services/odometry/odometry_node_config.h"
#include "services/pose_cells/pose_cells_node_config.h"
#include "services/templates/templates_node_config.h"

namespace rslam::run {

struct RatSlamConfig {
  odometry::OdometryNodeConfig odometry;                   // .visual: the visual odometry
  templates::TemplatesNodeConfig templates;                // .library: the template library
  pose_cells::PoseCellsNodeConfig pose_cells;              // .network: the pose-cell network
  experience_map::ExperienceMapNodeConfig experience_map;  // .map: the experience map
};

// Fills every section from root over the defaults and validates. Throws ConfigError naming the
// key for unknown keys, wrong types and bad values, and naming the section for an unknown
// top-level section. Sections that configure other parts of the system (bus, service, camera,
// occupancy, explorer) are accepted and ignored, so a service config file can be reused; but a
// camera section that changes the frames (crop, anti_vignetting, undistort) is a ConfigError,
// because the runner does not apply it and would build a different map than the services.
RatSlamConfig RatSlamConfigFromYaml(const YAML::Node& root);

// Overlays `overlay` onto `base` (maps merged key by key, everything else replaced).
void MergeYaml(YAML::Node& base, const YAML::Node& overlay);

// A preset name -> its file: $RSLAM_PRESET_DIR/<name>.yaml, then <fallback_dir>/<name>.yaml.
// Throws ConfigError("preset", ...) listing the places it looked.
std::filesystem::path FindPreset(const std::string& name, const std::filesystem::path& fallback_dir);

// The YAML document of `rslam run`: the preset (when not empty), then the config file (when not
// empty) over it, then each "section.key=value" override. Throws ConfigError.
YAML::Node ComposeRunYaml(const std::filesystem::path& preset_file, const std::string& config_file,
                          const std::vector<std::string>& overrides);

}  // namespace rslam::run
