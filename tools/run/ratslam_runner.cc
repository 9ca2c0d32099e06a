#include "tools/run/ratslam_runner.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace rslam::run {

namespace {

using Clock = std::chrono::steady_clock;

double MicrosSince(Clock::time_point start) {
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count();
}

experience_map::ExperienceAction::Kind ToExperienceKind(pose_cells::Action::Kind kind) {
  using In = pose_cells::Action::Kind;
  using Out = experience_map::ExperienceAction::Kind;
  switch (kind) {
    case In::kNone: return Out::kNone;
    case In::kCreate: return Out::kCreate;
    case In::kLink: return Out::kLink;
    case In::kSet: return Out::kSet;
  }
  throw std::invalid_argument("unknown pose-cell action kind");
}

}  // namespace

experience_map::ExperienceAction ToExperienceAction(const pose_cells::Action& a) {
  experience_map::ExperienceAction e;
  e.kind = ToExperienceKind(a.kind);
  e.experience_id = a.experience_id;
  e.from_experience_id = a.from_experience_id;
  e.template_id = a.template_id;
  e.relative_angle_rad = a.relative_angle_rad;
  e.pc_x = a.pc_x;
  e.pc_y = a.pc_y;
  e.pc_th = a.pc_th;
  e.sequence = a.sequence;
  return e;
}

cv::Mat ToGrey(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("empty image");
  if (image.depth() != CV_8U) throw std::invalid_argument("image is not 8 bits per channel");
  switch (image.channels()) {
    case 1:
      return image;
    case 3: {
      cv::Mat grey;
      cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
      return grey;
    }
    case 4: {
      cv::Mat grey;
      cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
      return grey;
    }
    default:
      throw std::invalid_argument("image has " + std::to_string(image.channels()) +
                                  " channels (expected 1, 3 or 4)");
  }
}

RatSlamRunner::RatSlamRunner(const RatSlamConfig& config)
    : config_(config),
      odometry_(config.odometry),
      templates_(config.templates),
      pose_cells_(config.pose_cells),
      map_(config.experience_map) {}

FrameRecord RatSlamRunner::ProcessFrame(const cv::Mat& image, int64_t stamp_ns) {
  FrameRecord record;
  record.frame_index = frames_;
  record.stamp_ns = stamp_ns;
  const bool first = !has_previous_stamp_;
  if (!first) {
    if (stamp_ns <= previous_stamp_ns_) {
      throw std::invalid_argument("frame " + std::to_string(frames_) + ": stamp " + std::to_string(stamp_ns) +
                                  " ns is not after the previous frame's " + std::to_string(previous_stamp_ns_) +
                                  " ns");
    }
    record.dt_s = static_cast<double>(stamp_ns - previous_stamp_ns_) * 1e-9;
  }

  auto start = Clock::now();
  const cv::Mat grey = ToGrey(image);
  // The first frame only primes the odometry's profile: its velocity is zero whatever dt is, but
  // Update still checks dt, so it gets the nominal period.
  const double odometry_dt = first ? 1.0 / config_.odometry.camera_hz : record.dt_s;
  record.velocity = odometry_.Update(grey, odometry_dt);
  if (first) record.velocity = odometry::Velocity{};
  record.micros.odometry = MicrosSince(start);

  start = Clock::now();
  record.view = templates_.MatchOrLearn(grey);
  record.micros.templates = MicrosSince(start);

  // Stamps are committed only once the image stages accepted the frame.
  has_previous_stamp_ = true;
  previous_stamp_ns_ = stamp_ns;

  start = Clock::now();
  record.action = pose_cells_.ProcessFrame(record.velocity.vtrans, record.velocity.vrot, record.dt_s,
                                           record.view.template_id, record.view.is_new,
                                           record.view.relative_angle_rad);
  record.micros.pose_cells = MicrosSince(start);

  start = Clock::now();
  ApplyToMap(record.velocity, record.dt_s, record.action);
  record.micros.experience_map = MicrosSince(start);
  ++frames_;
  return record;
}

pose_cells::Action RatSlamRunner::IntegrateMeasurements(const odometry::Velocity& velocity, double dt_s,
                                                        const templates::ViewMatch& view) {
  if (view.template_id >= templates_.size()) {
    throw std::invalid_argument("template " + std::to_string(view.template_id) + " is not in the library (" +
                                std::to_string(templates_.size()) + " templates)");
  }
  const pose_cells::Action action = pose_cells_.ProcessFrame(velocity.vtrans, velocity.vrot, dt_s, view.template_id,
                                                             view.is_new, view.relative_angle_rad);
  ApplyToMap(velocity, dt_s, action);
  ++frames_;
  return action;
}

uint32_t RatSlamRunner::LearnTemplate(const cv::Mat& image) { return templates_.Learn(ToGrey(image)); }

void RatSlamRunner::ApplyToMap(const odometry::Velocity& velocity, double dt_s, const pose_cells::Action& action) {
  map_.Integrate(velocity.vtrans, velocity.vrot, dt_s);
  const experience_map::ExperienceAction applied = ToExperienceAction(action);
  const size_t links_before = map_.links().size();
  map_.Apply(applied);
  if (action.kind == pose_cells::Action::Kind::kLink) {
    ++loop_closures_;
    if (map_.links().size() > links_before) {
      loop_closure_links_.emplace(action.from_experience_id, action.experience_id);
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
  RelaxResult result;
  double error = RmsLinkError();
  result.rms_link_error_m = error;
  if (map_.links().empty()) {
    result.converged = true;
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
