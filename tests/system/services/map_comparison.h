#pragma once
// Experience maps from different runs side by side: the in-process runner's (`rslam run`) and
// the experience-map service's experience_map/map snapshots. Two runs of the same frames must
// agree on every experience (id, template, pose, pose-cell coordinates) and link.

#include <cstdint>
#include <string>
#include <vector>

#include "rslam/msg/all_messages.h"
#include "tools/run/ratslam_runner.h"

namespace rslam::system_test {

struct MapRecord {
  std::vector<msg::Experience> experiences;
  std::vector<msg::ExperienceLink> links;
  uint32_t current_experience_id = 0;
};

// The runner's map in the snapshot's form (pose-cell coordinates as float, like the message).
MapRecord MapOfRunner(const run::RatSlamRunner& runner);
MapRecord MapOfSnapshot(const msg::ExperienceMap& snapshot);

struct MapDifference {
  std::string description;         // "" when the maps agree within the tolerance
  double max_abs_difference = 0;   // largest difference of any position, angle, distance, time
};

// Counts, ids, templates and loop-closure flags must be equal; numbers within tolerance.
MapDifference CompareMaps(const MapRecord& expected, const MapRecord& actual, double tolerance);

// "E experiences, L links (C loop closures), T templates"
std::string Summary(const MapRecord& map);

}  // namespace rslam::system_test
