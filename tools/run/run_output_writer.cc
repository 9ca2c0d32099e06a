#include "tools/run/run_output_writer.h"

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "tools/run/experience_map_image.h"
#include "tools/run/template_curve_image.h"

namespace rslam::run {

namespace {

std::ofstream OpenForWriting(const std::filesystem::path& file) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
  return out;
}

void Close(std::ofstream& out, const std::filesystem::path& file) {
  out.flush();
  if (!out) throw std::runtime_error(file.string() + ": write failed");
}

// Fixed notation, enough digits to round-trip the map to a micrometre, and the same text for
// the same number on every run (so two runs can be compared byte for byte).
std::string Number(double value) {
  value = std::round(value * 1e9) * 1e-9;
  if (value == 0.0) value = 0.0;  // no "-0.000000000"
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.9f", value);
  return buffer;
}

nlohmann::json StageJson(const StageMicroseconds& s) {
  return {{"odometry", s.odometry},
          {"templates", s.templates},
          {"pose_cells", s.pose_cells},
          {"experience_map", s.experience_map}};
}

}  // namespace

nlohmann::json MakeSummary(const RatSlamRunner& runner, const RunStatistics& statistics, const RelaxResult& relax,
                           const RunDescription& description) {
  const auto& map = runner.experience_map();
  nlohmann::json summary;
  summary["frames"] = statistics.frames();
  summary["templates"] = runner.templates().size();
  summary["experiences"] = map.experiences().size();
  summary["links"] = map.links().size();
  summary["loop_closures"] = runner.loop_closures();
  summary["fps_core"] = statistics.CoreFramesPerSecond();
  // Frames whose motion was lost the way the services lose it (see RatSlamRunner).
  summary["odometry_restarts"] = runner.odometry_restarts();
  summary["refused_velocities"] = runner.refused_velocities();
  summary["refused_actions"] = runner.refused_actions();
  summary["ms_per_frame"] = StageJson(statistics.MeanMilliseconds());
  summary["preset"] = description.preset;
  summary["config_file"] = description.config_file;
  summary["source"] = description.source;
  summary["relaxed"] = relax.converged;
  summary["relax_sweeps"] = relax.sweeps;
  summary["rms_link_error_m"] = relax.rms_link_error_m;
  summary["max_link_error_m"] = map.MaxLinkError();
  summary["wall_seconds"] = description.wall_seconds;
  return summary;
}

void WriteSummaryJson(const std::filesystem::path& file, const nlohmann::json& summary) {
  std::ofstream out = OpenForWriting(file);
  out << summary.dump(2) << "\n";
  Close(out, file);
}

void WriteExperiencesCsv(const std::filesystem::path& file, const experience_map::ExperienceMap& map) {
  std::ofstream out = OpenForWriting(file);
  out << "id,x,y,theta,template_id\n";
  for (const auto& e : map.experiences()) {
    out << e.id << ',' << Number(e.x_m) << ',' << Number(e.y_m) << ',' << Number(e.th_rad) << ',' << e.template_id
        << '\n';
  }
  Close(out, file);
}

void WriteTemplatesCsv(const std::filesystem::path& file, const RunStatistics& statistics) {
  std::ofstream out = OpenForWriting(file);
  out << "frame,stamp_ns,template_id,is_new,template_count\n";
  for (const auto& p : statistics.template_curve()) {
    out << p.frame << ',' << p.stamp_ns << ',' << p.template_id << ',' << (p.is_new ? 1 : 0) << ',' << p.template_count
        << '\n';
  }
  Close(out, file);
}

void WritePng(const std::filesystem::path& file, const cv::Mat& image) {
  bool written = false;
  try {
    written = cv::imwrite(file.string(), image);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(file.string() + ": cannot write image: " + e.what());
  }
  if (!written) throw std::runtime_error(file.string() + ": cannot write image");
}

void WriteRunOutputs(const std::filesystem::path& folder, const RatSlamRunner& runner, const RunStatistics& statistics,
                     const nlohmann::json& summary) {
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error || !std::filesystem::is_directory(folder)) {
    throw std::runtime_error(folder.string() + ": cannot create the output folder" +
                             (error ? " (" + error.message() + ")" : std::string()));
  }
  WriteExperiencesCsv(folder / "experiences.csv", runner.experience_map());
  WriteTemplatesCsv(folder / "templates.csv", statistics);
  WritePng(folder / "experience_map.png", DrawExperienceMap(runner.experience_map(), runner.loop_closure_links()));
  WritePng(folder / "templates.png", DrawTemplateCurve(statistics.template_curve()));
  // Last, so a summary means the other files are complete.
  WriteSummaryJson(folder / "summary.json", summary);
}

}  // namespace rslam::run
