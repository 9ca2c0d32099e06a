#include "tools/run/ratslam_runner.h"

#include "common/image/crop.h"
#include "services/experience_map/experience_action_message.h"
#include "services/pose_cells/pose_cell_action_message.h"
#include "tools/run/grey_rows.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace rslam::run {

namespace {

using Clock = std::chrono::steady_clock;

double MicrosSince(Clock::time_point start) {
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count();
}

// The rows [begin, end) of a frame of `rows` rows that the odometry's two crops and the template
// crop cover (a crop's y_max of -1 is the image height, as the stages resolve it). All rows when
// a crop does not fit: the stage then refuses the frame with its own message.
std::pair<int, int> RowsTheStagesRead(const RatSlamConfig& config, int rows) {
  const auto& odometry = config.odometry.visual;
  const auto& templates = config.templates.library;
  const std::pair<int, int> crops[] = {
      {odometry.vtrans_image_y_min, odometry.vtrans_image_y_max},
      {odometry.vrot_image_y_min, odometry.vrot_image_y_max},
      {templates.image_crop_y_min, templates.image_crop_y_max},
  };
  int begin = rows, end = 0;
  for (auto [y_min, y_max] : crops) {
    const auto crop = FitCrop(0, -1, y_min, y_max, cv::Size(1, rows));
    if (!crop) return {0, rows};  // the stage itself refuses the frame, naming its crop
    begin = std::min(begin, crop->y);
    end = std::max(end, crop->y + crop->height);
  }
  return {begin, end};
}

}  // namespace

cv::Mat ToGrey(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("empty image");
  if (image.depth() != CV_8U) throw std::invalid_argument("image is not 8 bits per channel");
  cv::Mat grey;
  switch (image.channels()) {
    case 1: return image;
    case 3: cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY); return grey;
    case 4: cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY); return grey;
    default:
      throw std::invalid_argument("image has " + std::to_string(image.channels()) + " channels (expected 1, 3 or 4)");
  }
}

RatSlamRunner::RatSlamRunner(const RatSlamConfig& config)
    : config_(config),
      odometry_(odometry::WithFloorCameraTilt(config.odometry.visual, config.odometry.floor)),
      templates_(config.templates.library),
      pose_cells_(config.pose_cells.network),
      map_(config.experience_map.map) {}

FrameRecord RatSlamRunner::ProcessFrame(const cv::Mat& image, int64_t stamp_ns) {
  if (has_previous_stamp_ && stamp_ns <= previous_stamp_ns_) {
    throw std::invalid_argument("frame " + std::to_string(frames_) + ": stamp " + std::to_string(stamp_ns) +
                                " ns is not after the previous frame's " + std::to_string(previous_stamp_ns_) + " ns");
  }
  FrameRecord record;
  record.frame_index = frames_;
  record.stamp_ns = stamp_ns;

  // Odometry service. Only the rows the crops cover are converted (the stages read nothing
  // else, so the result is that of converting the whole frame; see grey_rows.h).
  auto start = Clock::now();
  if (image.empty()) throw std::invalid_argument("empty image");
  const auto [row_begin, row_end] = RowsTheStagesRead(config_, image.rows);
  const cv::Mat grey = ToGreyRows(image, row_begin, row_end, grey_buffer_);
  bool restart = !has_previous_stamp_;
  if (!restart) {
    record.dt_s = static_cast<double>(stamp_ns - previous_stamp_ns_) * 1e-9;
    restart = grey.size() != previous_size_ || record.dt_s > config_.odometry.max_frame_gap_s;
    if (restart) ++odometry_restarts_;
  }
  if (restart) {
    odometry_.Reset();
    record.dt_s = 0.0;
  }
  record.velocity = odometry_.Update(grey, restart ? 1.0 / config_.odometry.visual.camera_hz : record.dt_s);
  has_previous_stamp_ = true;
  previous_stamp_ns_ = stamp_ns;
  previous_size_ = grey.size();
  record.micros.odometry = MicrosSince(start);

  // Templates service.
  start = Clock::now();
  record.view = templates::AsPublished(templates_.MatchOrLearn(grey));
  record.micros.templates = MicrosSince(start);

  record.action = PoseCellsAndMap(record.velocity.vtrans, record.velocity.vrot, record.dt_s, stamp_ns, record.view);
  record.micros.pose_cells = last_pose_cells_micros_;
  record.micros.experience_map = last_map_micros_;
  ++frames_;
  return record;
}

pose_cells::Action RatSlamRunner::PoseCellsAndMap(double vtrans, double vrot, double dt_s, int64_t stamp_ns,
                                                  const templates::ViewMatch& view) {
  // Pose-cell service: odometry it would refuse as malformed is replaced by "no motion".
  auto start = Clock::now();
  const auto& limits = config_.pose_cells;
  if (dt_s > limits.max_dt_s || std::abs(vtrans) > limits.max_vtrans_mps || std::abs(vrot) > limits.max_vrot_radps) {
    ++refused_velocities_;
    vtrans = vrot = 0.0;
    dt_s = has_last_frame_ && stamp_ns > last_frame_stamp_ns_
               ? std::min(limits.max_dt_s, static_cast<double>(stamp_ns - last_frame_stamp_ns_) * 1e-9)
               : 0.0;
  }
  const pose_cells::Action action = pose_cells_.ProcessFrame(vtrans, vrot, dt_s, view);
  has_last_frame_ = true;
  last_frame_stamp_ns_ = stamp_ns;
  last_pose_cells_micros_ = MicrosSince(start);

  start = Clock::now();
  ApplyToMap(action, vtrans, vrot, dt_s);
  last_map_micros_ = MicrosSince(start);
  return action;
}

pose_cells::Action RatSlamRunner::IntegrateMeasurements(const odometry::Velocity& velocity, double dt_s,
                                                        const templates::ViewMatch& view) {
  if (view.template_id >= templates_.size()) {
    throw std::invalid_argument("template " + std::to_string(view.template_id) + " is not in the library (" +
                                std::to_string(templates_.size()) + " templates)");
  }
  if (!std::isfinite(dt_s) || dt_s < 0) throw std::invalid_argument("dt must be finite and >= 0");
  synthetic_stamp_ns_ += static_cast<int64_t>(dt_s * 1e9);
  const pose_cells::Action action = PoseCellsAndMap(velocity.vtrans, velocity.vrot, dt_s, synthetic_stamp_ns_, view);
  ++frames_;
  return action;
}

uint32_t RatSlamRunner::LearnTemplate(const cv::Mat& image) { return templates_.Learn(ToGrey(image)); }

void RatSlamRunner::ApplyToMap(const pose_cells::Action& action, double vtrans, double vrot, double dt_s) {
  // The action as the experience-map service receives it; a message it would refuse (dt beyond
  // its max_dt_s) keeps its place in the sequence but nothing of it is applied.
  const msg::PoseCellAction message = pose_cells::ToActionMessage(action, next_action_seq_++, vtrans, vrot, dt_s);
  if (message.dt_s > config_.experience_map.max_dt_s) {
    ++refused_actions_;
    return;
  }
  const size_t links_before = map_.links().size();
  if (!experience_map::ApplyActionMessage(map_, message).ids_refused.empty()) {
    ++refused_actions_;
    return;
  }
  if (message.kind == msg::ActionKind::ACTION_LINK) {
    ++loop_closures_;
    if (map_.links().size() > links_before) {
      loop_closure_links_.emplace(message.from_experience_id, message.experience_id);
    }
  }
}

double RatSlamRunner::RmsLinkError() const {
  const auto& experiences = map_.experiences();
  const auto& links = map_.links();
  if (links.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& link : links) {
    const auto& from = experiences[link.from_id];
    const auto& to = experiences[link.to_id];
    const double ex = from.x_m + link.d_m * std::cos(from.th_rad + link.heading_rad) - to.x_m;
    const double ey = from.y_m + link.d_m * std::sin(from.th_rad + link.heading_rad) - to.y_m;
    sum += ex * ex + ey * ey;
  }
  return std::sqrt(sum / static_cast<double>(links.size()));
}

RelaxResult RatSlamRunner::RelaxToConvergence(double relative_tolerance, int max_sweeps) {
  constexpr int kSweepsPerBatch = 10;
  constexpr int kGraphSteps = 20;
  constexpr double kGraphStepTolerance = 1e-6;  // m and rad
  RelaxResult result;
  double error = RmsLinkError();
  result.rms_link_error_m = error;
  if (map_.links().empty()) {
    result.converged = true;
    return result;
  }
  if (map_.config().exp_graph_optimisation) {  // least squares: Gauss-Newton steps, not sweeps
    const experience_map::PoseGraphResult steps = map_.OptimiseGraph(kGraphSteps, kGraphStepTolerance);
    result.sweeps = steps.steps;
    result.converged = steps.converged;
    const double next = RmsLinkError();
    result.last_change_m = std::abs(next - error);
    result.rms_link_error_m = next;
    return result;
  }
  while (result.sweeps < max_sweeps) {
    const int batch = std::min(kSweepsPerBatch, max_sweeps - result.sweeps);
    map_.Relax(batch);
    result.sweeps += batch;
    const double next = RmsLinkError();
    result.last_change_m = std::abs(next - error);
    result.rms_link_error_m = next;
    error = next;
    if (result.last_change_m <= std::max(1e-9, relative_tolerance * next)) {
      result.converged = true;
      break;
    }
  }
  return result;
}

}  // namespace rslam::run
