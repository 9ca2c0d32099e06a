#pragma once
// The files `rslam run` leaves in its output folder:
//   summary.json        counts, speed, where the frames and config came from
//   experiences.csv     id,x,y,theta,template_id (metres, radians; after the final relaxation)
//   templates.csv       frame,stamp_ns,template_id,is_new,template_count (one row per frame)
//   experience_map.png  experiences and links (ExperienceMapImage)
//   templates.png       template count over frames (TemplateCurveImage)
// Every writer throws std::runtime_error naming the file when it cannot be written.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "services/experience_map/experience_map.h"
#include "tools/run/ratslam_runner.h"
#include "tools/run/run_statistics.h"

namespace rslam::run {

struct RunDescription {
  std::string preset;  // preset name, or "" when none
  std::string config_file;
  std::string source;         // what the frames came from
  double wall_seconds = 0.0;  // whole run including decoding
};

nlohmann::json MakeSummary(const RatSlamRunner& runner, const RunStatistics& statistics, const RelaxResult& relax,
                           const RunDescription& description);

void WriteSummaryJson(const std::filesystem::path& file, const nlohmann::json& summary);
void WriteExperiencesCsv(const std::filesystem::path& file, const experience_map::ExperienceMap& map);
void WriteTemplatesCsv(const std::filesystem::path& file, const RunStatistics& statistics);
void WritePng(const std::filesystem::path& file, const cv::Mat& image);

// All five files into folder (created if needed).
void WriteRunOutputs(const std::filesystem::path& folder, const RatSlamRunner& runner, const RunStatistics& statistics,
                     const nlohmann::json& summary);

}  // namespace rslam::run
