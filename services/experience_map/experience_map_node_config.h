#pragma once
// Configuration of the experience-map service (YAML section `experience_map`). The map's keys
// (OpenRatSLAM names, see experience_map_config.h) sit at the top of the section, so a preset
// file's `experience_map:` section configures the service directly.

#include <cmath>
#include <string>

#include "common/config/config_error.h"
#include "services/experience_map/experience_map_config.h"

namespace rslam::experience_map {

struct ExperienceMapNodeConfig {
  ExperienceMapConfig map;
  // experience_map/map snapshots: after a change, at most every this many applied actions...
  int map_publish_period_frames = 10;
  // ...and always once no action came for this long, so the latest snapshot (which a restarted
  // pose-cell service resynchronises from) catches up with the last applied action.
  double idle_publish_s = 0.2;
  // A missing action_seq is given up (logged, counted, skipped) once this many later actions
  // wait behind it or it has been missing this long.
  int gap_window_actions = 200;
  double gap_timeout_s = 2.0;
  double max_dt_s = 60.0;  // actions carrying a larger frame interval are refused
  // Map files (the state-file format): loaded at start instead of the saved state, merged into
  // the map at start (ids appended, unanchored), written on shutdown.
  std::string load_map;
  std::string merge_map;
  std::string save_map;

  template <class V>
  void VisitFields(V& v) {
    map.VisitFields(v);
    v("map_publish_period_frames", map_publish_period_frames,
      "at most one experience_map/map snapshot per this many applied actions while the map changes");
    v("idle_publish_s", idle_publish_s,
      "publish a catch-up snapshot once no action came for this long (s)");
    v("gap_window_actions", gap_window_actions,
      "a missing action is skipped once this many later actions wait behind it");
    v("gap_timeout_s", gap_timeout_s, "a missing action is skipped after this many seconds");
    v("max_dt_s", max_dt_s, "largest accepted frame interval in an action (s)");
    v("load_map", load_map, "map file to start from instead of the saved state (empty = none)");
    v("merge_map", merge_map, "map file merged into the map at start (empty = none)");
    v("save_map", save_map, "map file written on shutdown (empty = none)");
  }

  void Validate() const {
    map.Validate();
    Require(map_publish_period_frames >= 1, "map_publish_period_frames", "must be >= 1");
    Require(std::isfinite(idle_publish_s) && idle_publish_s > 0 && idle_publish_s <= 60, "idle_publish_s",
            "must be in (0, 60]");
    Require(gap_window_actions >= 1, "gap_window_actions", "must be >= 1");
    Require(std::isfinite(gap_timeout_s) && gap_timeout_s > 0, "gap_timeout_s", "must be positive");
    Require(std::isfinite(max_dt_s) && max_dt_s > 0, "max_dt_s", "must be positive");
  }
};

}  // namespace rslam::experience_map
