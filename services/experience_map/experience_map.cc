#include "services/experience_map/experience_map.h"

#include "services/experience_map/pose_graph.h"
#include "services/experience_map/scan_registration.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>
#include <queue>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

namespace rslam::experience_map {
namespace {

constexpr double kPi = std::numbers::pi;

[[noreturn]] void Reject(const std::string& why) {
  throw std::invalid_argument("experience map: " + why);
}

std::string Id(uint32_t id) { return id == kNoExperience ? std::string("none") : std::to_string(id); }

// exp_scan_links: floor-boundary points are kept one per cell of this size.
const ScanRegistrationOptions kScanRegistration;

// exp_manhattan_recapture_one_axis_turn_rad: offsets each axis must give to count as both axes'.
constexpr long kRecaptureFromEachAxis = 2;

int64_t ScanCell(const Eigen::Vector2f& p) {
  const auto cell = [](float v) { return static_cast<int64_t>(std::floor(v / kScanRegistration.cell_m)); };
  return (cell(p.x()) << 32) ^ (cell(p.y()) & 0xffffffff);
}

}  // namespace

ExperienceMap::ExperienceMap(const ExperienceMapConfig& config)
    : config_((config.Validate(), config)),
      accum_facing_(WrapAngle(config.exp_initial_em_deg * kPi / 180.0)) {}

void ExperienceMap::Integrate(double vtrans_mps, double vrot_radps, double dt_s) {
  if (!std::isfinite(vtrans_mps)) Reject("vtrans is not finite");
  if (!std::isfinite(vrot_radps)) Reject("vrot is not finite");
  if (!std::isfinite(dt_s) || dt_s < 0) Reject("dt must be finite and >= 0");
  const double dist = vtrans_mps * dt_s;
  // OpenRatSLAM order: turn, then move along the new facing.
  accum_facing_ = WrapAngle(accum_facing_ + vrot_radps * dt_s);
  turned_since_hold_rad_ += std::abs(vrot_radps * dt_s);
  driven_since_recognition_m_ += std::abs(dist);
  moved_this_frame_ = dist != 0.0 || vrot_radps * dt_s != 0.0;
  accum_x_ += dist * std::cos(accum_facing_);
  accum_y_ += dist * std::sin(accum_facing_);
  accum_time_ += dt_s;
  if (config_.exp_bridge_recognitions) {
    const double bridge_facing = accum_facing_ + bridge_facing_offset_;  // in bridge_from_'s frame
    bridge_x_ += dist * std::cos(bridge_facing);
    bridge_y_ += dist * std::sin(bridge_facing);
    bridge_time_ += dt_s;
  }
}

void ExperienceMap::HoldHeading(double wall_direction_rad) {
  if (!std::isfinite(wall_direction_rad)) Reject("wall direction is not finite");
  if (!config_.exp_manhattan) return;
  constexpr double kMinAgreement = 0.9;
  const double direction = accum_facing_ + wall_direction_rad;
  if (has_current_ && !experiences_[current_].wall_rad) {
    experiences_[current_].wall_rad = std::remainder(direction - experiences_[current_].th_rad, kPi / 2.0);
    if (manhattan_axes_ && config_.exp_manhattan_sigma_rad > 0) graph_pending_ = true;
  }
  if (!manhattan_axes_) {
    // The latest exp_manhattan_reference_frames directions, a window sliding one at a time: a
    // stretch of walls that agree is found wherever it starts, before the heading drifts.
    const size_t frames = static_cast<size_t>(config_.exp_manhattan_reference_frames);
    manhattan_window_.push_back(direction);
    if (manhattan_window_.size() > frames) manhattan_window_.pop_front();
    if (manhattan_window_.size() < frames) return;
    QuarterTurnMean reference;
    for (double d : manhattan_window_) reference.Add(d);
    if (reference.Agreement() >= kMinAgreement * static_cast<double>(frames)) {
      manhattan_axes_ = reference.Mean();
      manhattan_window_.clear();
    }
    return;
  }
  const double offset = std::remainder(direction - *manhattan_axes_, kPi / 2.0);
  const double gate = std::min(config_.exp_manhattan_max_offset_rad,
                               config_.exp_manhattan_min_offset_rad +
                                   config_.exp_manhattan_offset_per_rad_turned * turned_since_hold_rad_);
  if (std::abs(offset) > gate) {
    // A heading that drifted past the widest gate is never pulled back by walls on the axes: they
    // all come the same offset off. Walls off the axes (a funnel's, a round table's chords) come
    // at offsets that differ as the robot turns. So exp_manhattan_recapture_frames offsets in a
    // row past the widest gate, if they agree within exp_manhattan_recapture_spread_rad over
    // exp_manhattan_recapture_turn_rad of turning, are the heading's drift: taken out at once.
    // Not past exp_manhattan_recapture_max_rad: walls at 45 degrees to the axes are as far from
    // one axis as from the other. With exp_manhattan_recapture_inside_widest the offsets past the
    // gate of the moment count too: after a misread turn a wall held weakly (tapered) narrows
    // the gate again, and a heading 0.15-0.25 rad off then sits between the two gates, never held
    // while the robot drives on without turning much (AC26, session 69: 0.18 rad for 3,000
    // frames).
    const int frames = config_.exp_manhattan_recapture_frames;
    if (frames <= 0) return;
    if (std::abs(offset) <= config_.exp_manhattan_max_offset_rad && !config_.exp_manhattan_recapture_inside_widest) {
      offsets_outside_gate_.clear();  // the widest gate would hold it
      return;
    }
    // A standing robot reads the same wall off the same image again: one look, not many.
    if (config_.exp_manhattan_recapture_moving_frames && !moved_this_frame_) return;
    const long quarter_turns = std::lround((direction - *manhattan_axes_ - offset) / (kPi / 2.0));
    offsets_outside_gate_.push_back({offset, turned_since_hold_rad_, static_cast<int>(quarter_turns & 1)});
    if (offsets_outside_gate_.size() > static_cast<size_t>(frames)) offsets_outside_gate_.pop_front();
    const double turned = turned_since_hold_rad_ - offsets_outside_gate_.front().turned_rad;
    if (offsets_outside_gate_.size() < static_cast<size_t>(frames) || turned < config_.exp_manhattan_recapture_turn_rad)
      return;
    QuarterTurnMean offsets;
    for (const OutsideGate& o : offsets_outside_gate_) offsets.Add(o.offset_rad);
    const double mean = offsets.Mean();
    if (std::abs(mean) > config_.exp_manhattan_recapture_max_rad) return;
    for (const OutsideGate& o : offsets_outside_gate_)
      if (std::abs(std::remainder(o.offset_rad - mean, kPi / 2.0)) > config_.exp_manhattan_recapture_spread_rad) return;
    // A drift puts every wall the same offset off its axis; one wall off the axes, seen again and
    // again as the robot circles before it, gives offsets of one axis alone. So over more turning
    // than exp_manhattan_recapture_one_axis_turn_rad (the camera's field of view in the demo) walls
    // of both axes must agree (the recaptures judged: deploy/config/demo.yaml).
    if (config_.exp_manhattan_recapture_one_axis_turn_rad > 0 &&
        turned > config_.exp_manhattan_recapture_one_axis_turn_rad) {
      const auto axis1 = std::count_if(offsets_outside_gate_.begin(), offsets_outside_gate_.end(),
                                       [](const OutsideGate& o) { return o.axis == 1; });
      const auto axis0 = static_cast<long>(offsets_outside_gate_.size()) - axis1;
      if (std::min<long>(axis0, axis1) < kRecaptureFromEachAxis) return;
    }
    accum_facing_ = WrapAngle(accum_facing_ - mean);
    ++heading_recaptures_;
    recaptured_since_recognition_ = true;
  } else {
    // Tapered or not, a wall inside the gate counts as held: the gate narrows again below.
    const double taper = config_.exp_manhattan_taper ? Taper(offset, config_.exp_manhattan_max_offset_rad) : 1.0;
    accum_facing_ = WrapAngle(accum_facing_ - config_.exp_manhattan_gain * taper * offset);
  }
  turned_since_hold_rad_ = 0.0;
  offsets_outside_gate_.clear();
}

ExperienceMap::Observation ExperienceMap::ObservedFromCurrent(const ExperienceAction& a) const {
  // The robot faces relative_angle_rad from the experience it recognises (SetCurrent), so that
  // experience faces accum_facing_ - relative_angle_rad. OpenRatSLAM adds the angle here and in
  // on_set_experience alike, which puts twice the view's offset into every link it closes. The
  // robot stands at (offset_x_m, offset_y_m) in that experience's frame, so the experience is
  // that far behind it.
  const Experience& cur = experiences_[current_];
  const double facing = accum_facing_ - a.relative_angle_rad;
  const double c = std::cos(facing), s = std::sin(facing);
  const double x = accum_x_ - (c * a.offset_x_m - s * a.offset_y_m);
  const double y = accum_y_ - (s * a.offset_x_m + c * a.offset_y_m);
  return {std::hypot(x, y), WrapAngle(std::atan2(y, x) - cur.th_rad), WrapAngle(facing - cur.th_rad), accum_time_};
}

int ExperienceMap::FindLink(uint32_t from, uint32_t to) const {
  for (uint32_t li : links_from_[from]) {
    if (links_[li].to_id == to) return static_cast<int>(li);
  }
  return -1;
}

void ExperienceMap::AddLink(uint32_t from, uint32_t to, const Observation& o) {
  Link link;
  link.from_id = from;
  link.to_id = to;
  link.d_m = o.d;
  link.heading_rad = o.heading;
  link.facing_rad = o.facing;
  link.travel_time_s = o.time;
  link.traversals = 1;
  const uint32_t index = static_cast<uint32_t>(links_.size());
  links_.push_back(link);
  links_from_[from].push_back(index);
  links_to_[to].push_back(index);
}

void ExperienceMap::AverageInto(Link& link, const Observation& obs, bool reversed) {
  Observation o = obs;
  if (reversed) {
    // The observation runs to -> from: invert the transform into the link's direction.
    o.heading = WrapAngle(obs.heading - obs.facing + kPi);
    o.facing = WrapAngle(-obs.facing);
  }
  // 000 eq. 2 with A = n/(n+1), B = 1/(n+1): a running mean over the traversals.
  const double n = link.traversals;
  const double a = n / (n + 1.0), b = 1.0 / (n + 1.0);
  const double vx = a * link.d_m * std::cos(link.heading_rad) + b * o.d * std::cos(o.heading);
  const double vy = a * link.d_m * std::sin(link.heading_rad) + b * o.d * std::sin(o.heading);
  link.d_m = std::hypot(vx, vy);
  link.heading_rad = std::atan2(vy, vx);
  link.facing_rad = WrapAngle(link.facing_rad + b * WrapAngle(o.facing - link.facing_rad));
  link.travel_time_s = a * link.travel_time_s + b * o.time;
  link.traversals += 1;
}

void ExperienceMap::StartBridge() {
  bridge_from_ = current_;
  const double th = has_current_ ? experiences_[current_].th_rad : 0.0;
  const double c = std::cos(th), s = std::sin(th);
  bridge_x_ = c * accum_x_ + s * accum_y_;
  bridge_y_ = -s * accum_x_ + c * accum_y_;
  bridge_facing_offset_ = -th;
  bridge_time_ = accum_time_;
  bridge_pending_ = false;
}

ExperienceMap::Observation ExperienceMap::ObservedFromBridge() const {
  return {std::hypot(bridge_x_, bridge_y_), std::atan2(bridge_y_, bridge_x_),
          WrapAngle(accum_facing_ + bridge_facing_offset_), bridge_time_};
}

void ExperienceMap::SetCurrent(uint32_t id, const ExperienceAction& a) {
  if (has_current_ && id == current_) return;  // OpenRatSLAM keeps accumulating then
  current_ = id;
  has_current_ = true;
  const double th = experiences_[id].th_rad, c = std::cos(th), s = std::sin(th);
  accum_x_ = c * a.offset_x_m - s * a.offset_y_m;
  accum_y_ = s * a.offset_x_m + c * a.offset_y_m;
  accum_time_ = 0.0;
  accum_facing_ = WrapAngle(th + a.relative_angle_rad);
}

std::string ToString(const RecognitionRefusal& refusal) {
  char line[160];
  switch (refusal.gate) {
    case RecognitionRefusal::Gate::kJump:
      std::snprintf(line, sizeof(line),
                    "it would move the robot %.2f m from where the map has it "
                    "(exp_recognition_max_jump_m + _jump_per_m, at most _jump_cap_m: %.2f m here)",
                    refusal.value, refusal.limit);
      break;
    case RecognitionRefusal::Gate::kTurn:
      std::snprintf(line, sizeof(line), "it would turn the robot %.2f rad (exp_recognition_max_turn_rad: %.2f)",
                    refusal.value, refusal.limit);
      break;
    case RecognitionRefusal::Gate::kLink:
      std::snprintf(line, sizeof(line), "its link would be %.2f m long (exp_recognition_max_link_m: %.2f)",
                    refusal.value, refusal.limit);
      break;
  }
  return line;
}

std::optional<RecognitionRefusal> ExperienceMap::RefusalOf(const ExperienceAction& a, double link_m) const {
  using Gate = RecognitionRefusal::Gate;
  const Experience& e = experiences_[a.experience_id];
  const Pose2D robot = RobotPose();
  // A set while the pose cells are on a place the map refused is their step from it to a neighbour
  // of it, not one along the map's stretch: a recognition of that neighbour, facing the view's angle
  // as a link does (a link refused for its turn, then such a set moved the robot 7.9 m in a
  // recorded run; tools/demo/MEASUREMENTS.md, session 63).
  const bool takes_angle =
      a.kind == ExperienceAction::Kind::kLink || config_.exp_set_view_angle || pose_cells_current_.has_value();
  if (config_.exp_recognition_max_turn_rad > 0 && takes_angle) {
    const double turn = std::abs(WrapAngle(e.th_rad + a.relative_angle_rad - robot.theta));
    if (turn > config_.exp_recognition_max_turn_rad)
      return RecognitionRefusal{Gate::kTurn, turn, config_.exp_recognition_max_turn_rad};
  }
  if (config_.exp_recognition_max_link_m > 0 && a.kind == ExperienceAction::Kind::kLink &&
      link_m > config_.exp_recognition_max_link_m) {
    return RecognitionRefusal{Gate::kLink, link_m, config_.exp_recognition_max_link_m};
  }
  if (config_.exp_recognition_max_jump_m <= 0) return std::nullopt;
  const Pose2D placed = Compose(e.pose(), {a.offset_x_m, a.offset_y_m, 0.0});  // as SetCurrent puts it
  const double jump = std::hypot(placed.x - robot.x, placed.y - robot.y);
  double allowed =
      config_.exp_recognition_max_jump_m + config_.exp_recognition_jump_per_m * driven_since_recognition_m_;
  if (config_.exp_recognition_jump_cap_m > 0) allowed = std::min(allowed, config_.exp_recognition_jump_cap_m);
  if (jump > allowed) return RecognitionRefusal{Gate::kJump, jump, allowed};
  return std::nullopt;
}

void ExperienceMap::ValidateIds(const ExperienceAction& a) const {
  if (!std::isfinite(a.relative_angle_rad)) Reject("relative angle is not finite");
  if (!std::isfinite(a.offset_x_m) || !std::isfinite(a.offset_y_m)) Reject("view offset is not finite");
  const uint32_t n = static_cast<uint32_t>(experiences_.size());
  switch (a.kind) {
    case ExperienceAction::Kind::kNone:
      return;
    case ExperienceAction::Kind::kCreate:
      if (a.experience_id != n) {
        Reject("create of experience " + Id(a.experience_id) + " but the next id is " + std::to_string(n));
      }
      if (n == 0 && a.from_experience_id != kNoExperience) {
        Reject("first experience created from " + Id(a.from_experience_id) + " (expected none)");
      }
      if (n > 0 && !IsCurrent(a.from_experience_id)) {
        Reject("create from " + Id(a.from_experience_id) + " but the current experience is " + Id(current_));
      }
      if (!std::isfinite(a.pc_x) || !std::isfinite(a.pc_y) || !std::isfinite(a.pc_th)) {
        Reject("pose-cell position is not finite");
      }
      return;
    case ExperienceAction::Kind::kLink:
    case ExperienceAction::Kind::kSet:
      if (a.experience_id >= n) Reject("unknown experience " + Id(a.experience_id));
      if (!has_current_ || !IsCurrent(a.from_experience_id)) {
        Reject("action from " + Id(a.from_experience_id) + " but the current experience is " +
               (has_current_ ? Id(current_) : std::string("none")));
      }
      if (a.kind == ExperienceAction::Kind::kLink && a.experience_id == a.from_experience_id) {
        Reject("link from experience " + Id(a.experience_id) + " to itself");
      }
      return;
  }
  Reject("unknown action kind");
}

void ExperienceMap::Apply(const ExperienceAction& a) {
  ValidateIds(a);
  last_refusal_.reset();
  switch (a.kind) {
    case ExperienceAction::Kind::kNone:
      break;
    case ExperienceAction::Kind::kCreate: {
      Experience e;
      e.id = static_cast<uint32_t>(experiences_.size());
      if (has_current_) {
        const Experience& cur = experiences_[current_];
        e.x_m = cur.x_m + accum_x_;
        e.y_m = cur.y_m + accum_y_;
      } else {
        e.x_m = accum_x_;
        e.y_m = accum_y_;
      }
      e.th_rad = WrapAngle(accum_facing_);
      e.template_id = a.template_id;
      e.pc_x = a.pc_x;
      e.pc_y = a.pc_y;
      e.pc_th = a.pc_th;
      experiences_.push_back(e);
      links_from_.emplace_back();
      links_to_.emplace_back();
      if (has_current_) {
        if (config_.exp_bridge_recognitions && bridge_pending_) {
          AddLink(bridge_from_, e.id, ObservedFromBridge());
        } else {
          AddLink(current_, e.id, ObservedFromCurrent({}));
        }
      }
      SetCurrent(e.id, {});
      StartBridge();
      pose_cells_current_.reset();
      // The robot has left the experiences before e, so the stretch centred exp_scan_region
      // before it is complete.
      if (config_.exp_scan_links && config_.exp_graph_optimisation && e.id > static_cast<uint32_t>(config_.exp_scan_region)) {
        const uint32_t centre = e.id - 1 - static_cast<uint32_t>(config_.exp_scan_region);
        if (centre % static_cast<uint32_t>(config_.exp_scan_every) == 0) TryScanLink(centre);
      }
      break;
    }
    case ExperienceAction::Kind::kLink:
    case ExperienceAction::Kind::kSet: {
      const uint32_t to = a.experience_id;
      if (to == current_) {
        pose_cells_current_.reset();
        break;
      }
      const bool link_kind = a.kind == ExperienceAction::Kind::kLink;
      ExperienceAction recognised = a;
      if (!link_kind && !config_.exp_set_view_angle) {  // the angle at which nothing turns
        recognised.relative_angle_rad = WrapAngle(accum_facing_ - experiences_[to].th_rad);
      }
      const Observation o = ObservedFromCurrent(recognised);
      last_refusal_ = RefusalOf(a, o.d);
      if (last_refusal_) {
        pose_cells_current_ = to;
        ++refused_recognitions_;
        break;
      }
      pose_cells_current_.reset();
      const uint32_t local_ids = static_cast<uint32_t>(config_.exp_recognition_jump_local_ids);
      if ((to > current_ ? to - current_ : current_ - to) > local_ids) {
        driven_since_recognition_m_ = 0.0;
        recaptured_since_recognition_ = false;
      }
      bool changed = false;
      if (link_kind || config_.exp_average_repeated_links) {
        if (const int fwd = FindLink(current_, to); fwd >= 0) {
          AverageInto(links_[fwd], o, false);
          changed = true;
        } else if (const int back = FindLink(to, current_); back >= 0) {
          AverageInto(links_[back], o, true);
          changed = true;
        } else if (link_kind) {
          AddLink(current_, to, o);
          links_.back().closes_loop = true;
          changed = true;
        }
      }
      if (changed) {
        graph_pending_ = true;
        if (!config_.exp_graph_optimisation) SeedLocalRegion(current_, to);
      }
      const Pose2D dead_reckoned = RobotPose();
      SetCurrent(to, recognised);
      if (config_.exp_heading_correction < 1.0) {  // at 1 the recognised heading stands, bit for bit
        accum_facing_ = WrapAngle(dead_reckoned.theta +
                                  config_.exp_heading_correction * WrapAngle(accum_facing_ - dead_reckoned.theta));
      }
      if (config_.exp_position_correction < 1.0) {  // at 1 the robot is on the experience (OpenRatSLAM)
        const double keep = 1.0 - config_.exp_position_correction;
        accum_x_ = keep * (dead_reckoned.x - experiences_[to].x_m) + config_.exp_position_correction * accum_x_;
        accum_y_ = keep * (dead_reckoned.y - experiences_[to].y_m) + config_.exp_position_correction * accum_y_;
      }
      bridge_facing_offset_ += dead_reckoned.theta - accum_facing_;  // the bridge does not turn with it
      bridge_pending_ = true;
      break;
    }
  }
  if (a.kind != ExperienceAction::Kind::kNone) next_sequence_ = a.sequence + 1;
  if (config_.exp_graph_optimisation) {
    last_correction_ = 0.0;
    frames_since_graph_ = std::min(frames_since_graph_ + 1, config_.exp_graph_period_frames);
    if (graph_pending_ && frames_since_graph_ >= config_.exp_graph_period_frames) OptimiseGraph(config_.exp_graph_iterations);
  } else if (config_.exp_relax_budget_links == 0) {
    last_correction_ = 0.0;
    if (a.kind != ExperienceAction::Kind::kNone) Relax(config_.exp_loops);
  } else {
    CorrectBudgeted();
  }
}

void ExperienceMap::ObserveBoundary(std::span<const Eigen::Vector2f> points) {
  for (const Eigen::Vector2f& p : points)
    if (!p.allFinite()) Reject("floor boundary point is not finite");
  // Only while the robot is still at the experience it made last: a recognised place's frame holds
  // the walls of the visit that made it, not those a wrong recognition would put there.
  if (!config_.exp_scan_links || !has_current_ || current_ + 1 != experiences_.size()) return;
  Experience& e = experiences_[current_];
  const Pose2D robot = Between(e.pose(), RobotPose());  // in the experience's frame
  const double c = std::cos(robot.theta), s = std::sin(robot.theta);
  const double range2 = config_.exp_scan_range_m * config_.exp_scan_range_m;
  for (const Eigen::Vector2f& p : points) {
    if (p.cast<double>().squaredNorm() > range2) continue;
    const Eigen::Vector2f q(static_cast<float>(robot.x + c * p.x() - s * p.y()),
                            static_cast<float>(robot.y + s * p.x() + c * p.y()));
    const int64_t cell = ScanCell(q);
    if (std::none_of(e.scan.begin(), e.scan.end(), [cell](const Eigen::Vector2f& k) { return ScanCell(k) == cell; }))
      e.scan.push_back(q);
  }
}

std::vector<Eigen::Vector2f> ExperienceMap::StretchPoints(uint32_t centre, uint32_t end) const {
  const uint32_t region = static_cast<uint32_t>(config_.exp_scan_region);
  const Experience& c = experiences_[centre];
  std::vector<Eigen::Vector2f> out;
  std::unordered_set<int64_t> cells;
  for (uint32_t i = centre > region ? centre - region : 0; i < std::min(end, centre + region + 1); ++i) {
    const Experience& e = experiences_[i];
    const Pose2D at = Between(c.pose(), e.pose());
    const double cs = std::cos(at.theta), sn = std::sin(at.theta);
    for (const Eigen::Vector2f& p : e.scan) {
      const Eigen::Vector2f q(static_cast<float>(at.x + cs * p.x() - sn * p.y()),
                              static_cast<float>(at.y + sn * p.x() + cs * p.y()));
      if (cells.insert(ScanCell(q)).second) out.push_back(q);
    }
  }
  return out;
}

void ExperienceMap::TryScanLink(uint32_t a) {
  const uint32_t age = static_cast<uint32_t>(config_.exp_scan_min_age);
  if (a < age) return;
  const Experience& newer = experiences_[a];
  const uint32_t region = static_cast<uint32_t>(config_.exp_scan_region);
  // The old experiences within exp_scan_radius_m of a in the map, as visits (their ids more than
  // two regions apart: stretches that do not overlap), and the nearest of each.
  std::vector<std::pair<double, uint32_t>> visits;
  uint32_t previous = 0;
  for (uint32_t j = 0; j <= a - age; ++j) {
    const double d = std::hypot(experiences_[j].x_m - newer.x_m, experiences_[j].y_m - newer.y_m);
    if (d > config_.exp_scan_radius_m) continue;
    if (visits.empty() || j - previous > 2 * region)
      visits.emplace_back(d, j);
    else if (d <= visits.back().first)
      visits.back() = {d, j};
    previous = j;
  }
  std::sort(visits.begin(), visits.end());
  visits.resize(std::min(visits.size(), static_cast<size_t>(config_.exp_scan_visits)));
  std::erase_if(recent_scans_, [&](const RecentScan& s) {
    return a - s.scan.link.to_id > static_cast<uint32_t>(config_.exp_scan_confirm_ids);
  });
  if (visits.empty()) return;
  const std::vector<Eigen::Vector2f> source = StretchPoints(a, static_cast<uint32_t>(experiences_.size()));
  if (source.size() < static_cast<size_t>(config_.exp_scan_min_pairs)) return;
  for (const auto& [distance, older] : visits) RegisterStretch(a, older, source);
}

void ExperienceMap::RegisterStretch(uint32_t a, uint32_t older, const std::vector<Eigen::Vector2f>& source) {
  const uint32_t region = static_cast<uint32_t>(config_.exp_scan_region);
  const std::vector<Eigen::Vector2f> target = StretchPoints(older, a - region);  // the stretches do not overlap
  if (target.size() < static_cast<size_t>(config_.exp_scan_min_pairs)) return;
  const Pose2D guess = Between(experiences_[older].pose(), experiences_[a].pose());
  ++scan_registrations_;
  const std::optional<ScanRegistration> r = RegisterScans(target, source, guess, kScanRegistration);
  if (!r || r->pairs < config_.exp_scan_min_pairs || r->median_distance_m > config_.exp_scan_max_distance_m ||
      r->inlier_share < config_.exp_scan_min_inlier_share || r->weak_share() < config_.exp_scan_min_weak_share)
    return;
  const Pose2D correction = Between(guess, r->pose);
  if (std::hypot(correction.x, correction.y) > config_.exp_scan_max_correction_m ||
      std::abs(correction.theta) > config_.exp_scan_max_correction_rad)
    return;
  ScanLink scan;
  scan.link.from_id = older;
  scan.link.to_id = a;
  scan.link.d_m = std::hypot(r->pose.x, r->pose.y);
  scan.link.heading_rad = std::atan2(r->pose.y, r->pose.x);
  scan.link.facing_rad = r->pose.theta;
  scan.information = r->information;
  if (config_.exp_scan_confirm_ids > 0) {
    // Confirmed by any agreeing registration around an earlier experience (another stretch, so
    // another measurement); that one is kept too.
    bool confirmed = false;
    for (RecentScan& s : recent_scans_) {
      if (s.scan.link.to_id == a || !ScanLinksAgree(s.scan, scan)) continue;
      if (!s.kept) scan_links_.push_back(s.scan);
      s.kept = true;
      confirmed = true;
    }
    recent_scans_.push_back({scan, confirmed});
    if (!confirmed) return;
  }
  scan_links_.push_back(scan);
  graph_pending_ = true;
  // Not between a heading recapture and the next recognition: a recapture turns the map at the
  // robot, and whether it was right shows only in how older places line up after it. Scan links
  // turn the map by at most exp_scan_max_correction_rad, so those kept then tie the map to the
  // stretch drawn since, not to the older places; restarting the distance on them refused the
  // recognitions that would have undone a wrong recapture (AM70, session 77).
  if (config_.exp_recognition_jump_scan_restarts && !recaptured_since_recognition_)
    driven_since_recognition_m_ = std::min(driven_since_recognition_m_, DrivenSince(a));
}

double ExperienceMap::DrivenSince(uint32_t since) const {
  // Experiences are made one after another along the path.
  double d = std::hypot(accum_x_, accum_y_);
  for (uint32_t i = since; i + 1 < experiences_.size(); ++i)
    d += std::hypot(experiences_[i + 1].x_m - experiences_[i].x_m, experiences_[i + 1].y_m - experiences_[i].y_m);
  return d;
}

bool ExperienceMap::ScanLinksAgree(const ScanLink& a, const ScanLink& b) const {
  const auto pose = [this](uint32_t id) { return experiences_[id].pose(); };
  // b's newer end in a's older end's frame: through a's measurement and the map's newer stretch,
  // and through the map's older stretch and b's measurement.
  const Pose2D via_a = Compose(a.link.pose(), Between(pose(a.link.to_id), pose(b.link.to_id)));
  const Pose2D via_b = Compose(Between(pose(a.link.from_id), pose(b.link.from_id)), b.link.pose());
  return std::hypot(via_a.x - via_b.x, via_a.y - via_b.y) <= config_.exp_scan_confirm_m &&
         std::abs(WrapAngle(via_a.theta - via_b.theta)) <= config_.exp_scan_confirm_rad;
}

PoseGraphResult ExperienceMap::OptimiseGraph(int iterations, double stop_below) {
  PoseGraphSigmas sigmas{config_.exp_graph_link_sigma_m,    config_.exp_graph_link_sigma_rad,
                         config_.exp_graph_closure_sigma_m, config_.exp_graph_closure_sigma_rad,
                         config_.exp_graph_closure_robust_phi};
  sigmas.scan_m = config_.exp_graph_scan_sigma_m;
  const PoseGraphResult result = OptimisePoseGraph(
      experiences_, links_, scan_links_, sigmas,
      iterations, stop_below,
      manhattan_axes_ && config_.exp_manhattan_sigma_rad > 0
          ? std::optional<ManhattanAxes>({*manhattan_axes_, config_.exp_manhattan_sigma_rad, config_.exp_manhattan_max_offset_rad,
                                          config_.exp_manhattan_taper})
          : std::nullopt);
  last_correction_ = result.largest_change;
  graph_pending_ = false;
  frames_since_graph_ = 0;
  return result;
}

double ExperienceMap::RelaxLink(uint32_t index) {
  const Link& link = links_[index];
  Experience& from = experiences_[link.from_id];
  Experience& to = experiences_[link.to_id];
  const double alpha = config_.exp_correction;
  // Where `from` and the link say `to` should be; move both by alpha of the error (000 eq. 3).
  // Once a part of the map has settled, its corrections no longer change the angles' bits, and
  // the cosine and sine of the same angle are the same numbers: they are kept per link and
  // recomputed only when the angle's bits change (the trigonometry is most of a relaxation).
  const double angle = from.th_rad + link.heading_rad;
  if (index >= link_trig_.size()) link_trig_.resize(links_.size());
  LinkTrig& trig = link_trig_[index];
  if (std::bit_cast<uint64_t>(angle) != std::bit_cast<uint64_t>(trig.angle)) {
    trig.angle = angle;
    trig.cos = std::cos(angle);
    trig.sin = std::sin(angle);
  }
  const double lx = from.x_m + link.d_m * trig.cos;
  const double ly = from.y_m + link.d_m * trig.sin;
  const double ex = (to.x_m - lx) * alpha;
  const double ey = (to.y_m - ly) * alpha;
  from.x_m += ex;
  from.y_m += ey;
  to.x_m -= ex;
  to.y_m -= ey;
  const double df = WrapAngle(to.th_rad - (from.th_rad + link.facing_rad)) * alpha;
  from.th_rad = WrapAngle(from.th_rad + df);
  to.th_rad = WrapAngle(to.th_rad - df);
  return std::max({std::abs(ex), std::abs(ey), std::abs(df)});
}

void ExperienceMap::SeedLocalRegion(uint32_t a, uint32_t b) {
  local_region_.clear();
  const size_t limit = static_cast<size_t>(config_.exp_local_region_links);
  if (limit == 0) return;
  // Breadth-first from a and b. "Seen" marks are stamps of this call in arrays kept between
  // calls, so a seed (every frame that re-traverses or closes a link) allocates nothing.
  seen_experience_.resize(experiences_.size(), 0);
  seen_link_.resize(links_.size(), 0);
  if (++seed_stamp_ == 0) {  // the stamps wrapped: forget every old mark
    std::fill(seen_experience_.begin(), seen_experience_.end(), 0);
    std::fill(seen_link_.begin(), seen_link_.end(), 0);
    seed_stamp_ = 1;
  }
  seed_queue_.clear();
  for (uint32_t e : {a, b}) {
    if (seen_experience_[e] == seed_stamp_) continue;
    seen_experience_[e] = seed_stamp_;
    seed_queue_.push_back(e);
  }
  for (size_t head = 0; head < seed_queue_.size() && local_region_.size() < limit; ++head) {
    const uint32_t e = seed_queue_[head];
    for (const auto* list : {&links_from_[e], &links_to_[e]}) {
      for (uint32_t li : *list) {
        if (local_region_.size() >= limit) break;
        if (seen_link_[li] == seed_stamp_) continue;
        seen_link_[li] = seed_stamp_;
        local_region_.push_back(li);
        const Link& l = links_[li];
        const uint32_t other = l.from_id == e ? l.to_id : l.from_id;
        if (seen_experience_[other] != seed_stamp_) {
          seen_experience_[other] = seed_stamp_;
          seed_queue_.push_back(other);
        }
      }
    }
  }
}

int ExperienceMap::CorrectBudgeted() {
  int budget = config_.exp_relax_budget_links;
  int relaxed = 0;
  last_correction_ = 0.0;
  if (!local_region_.empty()) {
    double largest = 0.0;
    for (uint32_t li : local_region_) largest = std::max(largest, RelaxLink(li));
    last_correction_ = largest;
    relaxed += static_cast<int>(local_region_.size());
    budget -= static_cast<int>(local_region_.size());
    if (largest <= config_.exp_relax_tolerance) local_region_.clear();
  }
  if (links_.empty()) return relaxed;
  // Continue the global sweep; experiences without outgoing links also cost one unit, so the
  // work per frame is bounded whatever the map looks like.
  const uint32_t n = static_cast<uint32_t>(experiences_.size());
  while (budget > 0) {
    if (sweep_experience_ >= n) {
      sweep_experience_ = 0;
      sweep_link_ = 0;
    }
    const auto& out = links_from_[sweep_experience_];
    if (sweep_link_ < out.size()) {
      last_correction_ = std::max(last_correction_, RelaxLink(out[sweep_link_]));
      ++sweep_link_;
      ++relaxed;
    } else {
      ++sweep_experience_;
      sweep_link_ = 0;
    }
    --budget;
  }
  return relaxed;
}

void ExperienceMap::Relax(int iterations) {
  last_correction_ = 0.0;
  for (int i = 0; i < iterations; ++i) {
    for (uint32_t e = 0; e < experiences_.size(); ++e) {
      for (uint32_t li : links_from_[e]) last_correction_ = std::max(last_correction_, RelaxLink(li));
    }
  }
  sweep_experience_ = 0;
  sweep_link_ = 0;
  local_region_.clear();
}

std::vector<uint32_t> ExperienceMap::PathToGoal(uint32_t from_id, uint32_t goal_id) const {
  const uint32_t n = static_cast<uint32_t>(experiences_.size());
  if (from_id >= n) Reject("path start " + Id(from_id) + " is unknown");
  if (goal_id >= n) Reject("path goal " + Id(goal_id) + " is unknown");
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> time(n, inf);
  std::vector<uint32_t> previous(n, kNoExperience);
  using Item = std::pair<double, uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  time[from_id] = 0.0;
  heap.push({0.0, from_id});
  while (!heap.empty()) {
    const auto [t, e] = heap.top();
    heap.pop();
    if (t > time[e]) continue;
    if (e == goal_id) break;
    for (const auto* list : {&links_from_[e], &links_to_[e]}) {
      for (uint32_t li : *list) {
        const Link& l = links_[li];
        const uint32_t other = l.from_id == e ? l.to_id : l.from_id;
        const double candidate = t + l.travel_time_s;
        if (candidate < time[other]) {
          time[other] = candidate;
          previous[other] = e;
          heap.push({candidate, other});
        }
      }
    }
  }
  if (time[goal_id] == inf) return {};
  std::vector<uint32_t> path;
  for (uint32_t e = goal_id; e != kNoExperience; e = previous[e]) path.push_back(e);
  std::reverse(path.begin(), path.end());
  return path;
}

void ExperienceMap::MergeFrom(const ExperienceMap& other, const std::vector<MapAnchor>& anchors) {
  if (&other == this) Reject("cannot merge a map into itself");
  for (const MapAnchor& an : anchors) {
    if (an.this_id >= experiences_.size()) Reject("anchor refers to unknown experience " + Id(an.this_id));
    if (an.other_id >= other.experiences_.size()) {
      Reject("anchor refers to unknown experience " + Id(an.other_id) + " of the merged map");
    }
  }
  const uint32_t offset = static_cast<uint32_t>(experiences_.size());
  const uint32_t link_offset = static_cast<uint32_t>(links_.size());
  // Rigid transform placing other's first anchor on ours.
  double dth = 0.0, ox = 0.0, oy = 0.0, tx = 0.0, ty = 0.0;
  if (!anchors.empty()) {
    const Experience& mine = experiences_[anchors[0].this_id];
    const Experience& theirs = other.experiences_[anchors[0].other_id];
    dth = WrapAngle(mine.th_rad - theirs.th_rad);
    ox = theirs.x_m;
    oy = theirs.y_m;
    tx = mine.x_m;
    ty = mine.y_m;
  }
  const double c = std::cos(dth), s = std::sin(dth);
  for (const Experience& e : other.experiences_) {
    Experience copy = e;
    copy.id = e.id + offset;
    const double rx = e.x_m - ox, ry = e.y_m - oy;
    copy.x_m = tx + c * rx - s * ry;
    copy.y_m = ty + s * rx + c * ry;
    copy.th_rad = WrapAngle(e.th_rad + dth);
    if (anchors.empty()) copy.wall_rad.reset();  // a part of its own frame: our axes say nothing of it
    experiences_.push_back(copy);
    links_from_.emplace_back();
    links_to_.emplace_back();
  }
  for (const Link& l : other.links_) {
    Link copy = l;
    copy.from_id += offset;
    copy.to_id += offset;
    links_.push_back(copy);
    links_from_[copy.from_id].push_back(static_cast<uint32_t>(links_.size() - 1));
    links_to_[copy.to_id].push_back(static_cast<uint32_t>(links_.size() - 1));
  }
  (void)link_offset;
  for (ScanLink copy : other.scan_links_) {
    copy.link.from_id += offset;
    copy.link.to_id += offset;
    scan_links_.push_back(copy);
  }
  for (const MapAnchor& an : anchors) {
    AddLink(an.this_id, an.other_id + offset, {0.0, 0.0, 0.0, 0.0});
    links_.back().closes_loop = true;  // the two maps are joined where a place is recognised
  }
  if (!anchors.empty()) {
    graph_pending_ = true;
    if (!config_.exp_graph_optimisation) SeedLocalRegion(anchors[0].this_id, anchors[0].other_id + offset);
  }
}

Pose2D ExperienceMap::RobotPose() const {
  if (!has_current_) return {accum_x_, accum_y_, accum_facing_};
  const Experience& cur = experiences_[current_];
  return {cur.x_m + accum_x_, cur.y_m + accum_y_, accum_facing_};
}

double ExperienceMap::MaxLinkError() const {
  double worst = 0.0;
  for (const Link& l : links_) {
    const Experience& from = experiences_[l.from_id];
    const Experience& to = experiences_[l.to_id];
    const double lx = from.x_m + l.d_m * std::cos(from.th_rad + l.heading_rad);
    const double ly = from.y_m + l.d_m * std::sin(from.th_rad + l.heading_rad);
    worst = std::max(worst, std::hypot(to.x_m - lx, to.y_m - ly));
  }
  return worst;
}

proto::ExperienceMap ExperienceMap::Save() const {
  proto::ExperienceMap m;
  for (const Experience& e : experiences_) {
    auto* p = m.add_experiences();
    p->set_x_m(e.x_m);
    p->set_y_m(e.y_m);
    p->set_th_rad(e.th_rad);
    p->set_template_id(e.template_id);
    p->set_pc_x(e.pc_x);
    p->set_pc_y(e.pc_y);
    p->set_pc_th(e.pc_th);
    if (e.wall_rad) p->set_wall_rad(*e.wall_rad);
    for (const Eigen::Vector2f& q : e.scan) {
      p->add_scan_xy(q.x());
      p->add_scan_xy(q.y());
    }
  }
  const auto save_link = [](const Link& l, proto::Link* p) {
    p->set_from_id(l.from_id);
    p->set_to_id(l.to_id);
    p->set_d_m(l.d_m);
    p->set_heading_rad(l.heading_rad);
    p->set_facing_rad(l.facing_rad);
    p->set_travel_time_s(l.travel_time_s);
    p->set_traversals(l.traversals);
    p->set_closes_loop(l.closes_loop);
  };
  for (const Link& l : links_) save_link(l, m.add_links());
  const auto save_scan = [&](const ScanLink& l, proto::ScanLink* p) {
    save_link(l.link, p->mutable_link());
    const Eigen::Matrix3d& i = l.information;
    p->set_walls_xx(i(0, 0));
    p->set_walls_xy(i(0, 1));
    p->set_walls_yy(i(1, 1));
    p->set_turn_x(i(0, 2));
    p->set_turn_y(i(1, 2));
    p->set_turn_turn(i(2, 2));
  };
  for (const ScanLink& l : scan_links_) save_scan(l, m.add_scan_links());
  m.set_has_current(has_current_);
  m.set_current_id(current_);
  m.set_accum_x_m(accum_x_);
  m.set_accum_y_m(accum_y_);
  m.set_accum_facing_rad(accum_facing_);
  m.set_accum_time_s(accum_time_);
  m.set_sweep_experience(sweep_experience_);
  m.set_sweep_link(sweep_link_);
  for (uint32_t li : local_region_) m.add_local_region_links(li);
  m.set_next_sequence(next_sequence_);
  m.set_has_manhattan_axes(manhattan_axes_.has_value());
  m.set_manhattan_axes_rad(manhattan_axes_.value_or(0.0));
  for (double d : manhattan_window_) m.add_manhattan_window_rad(d);
  m.set_has_pose_cells_current(pose_cells_current_.has_value());
  m.set_pose_cells_current_id(pose_cells_current_.value_or(0));
  m.set_driven_since_recognition_m(driven_since_recognition_m_);
  m.set_recaptured_since_recognition(recaptured_since_recognition_);
  m.set_turned_since_hold_rad(turned_since_hold_rad_);
  for (const OutsideGate& o : offsets_outside_gate_) {
    m.add_outside_gate_offset_rad(o.offset_rad);
    m.add_outside_gate_turned_rad(o.turned_rad);
    m.add_outside_gate_axis(static_cast<uint32_t>(o.axis));
  }
  proto::Bridge* bridge = m.mutable_bridge();
  bridge->set_from_id(bridge_from_);
  bridge->set_x_m(bridge_x_);
  bridge->set_y_m(bridge_y_);
  bridge->set_time_s(bridge_time_);
  bridge->set_facing_offset_rad(bridge_facing_offset_);
  bridge->set_pending(bridge_pending_);
  for (const RecentScan& s : recent_scans_) {
    save_scan(s.scan, m.add_recent_scans());
    m.add_recent_scans_kept(s.kept);
  }
  m.set_graph_pending(graph_pending_);
  m.set_frames_since_graph(static_cast<uint32_t>(frames_since_graph_));
  m.set_refused_recognitions(refused_recognitions_);
  m.set_heading_recaptures(heading_recaptures_);
  m.set_scan_registrations(scan_registrations_);
  return m;
}

void ExperienceMap::Load(const proto::ExperienceMap& m) {
  const uint32_t n = static_cast<uint32_t>(m.experiences_size());
  const uint32_t nl = static_cast<uint32_t>(m.links_size());
  auto finite = [](std::initializer_list<double> values) {
    for (double v : values)
      if (!std::isfinite(v)) return false;
    return true;
  };
  for (const auto& e : m.experiences()) {
    if (!finite({e.x_m(), e.y_m(), e.th_rad(), e.pc_x(), e.pc_y(), e.pc_th(), e.wall_rad()})) {
      Reject("saved experience has non-finite numbers");
    }
    if (e.scan_xy_size() % 2 != 0 || !std::all_of(e.scan_xy().begin(), e.scan_xy().end(), [](float v) { return std::isfinite(v); }))
      Reject("saved experience's floor boundary is not finite (x, y) pairs");
  }
  const auto check_link = [&](const proto::Link& l) {
    if (l.from_id() >= n || l.to_id() >= n) Reject("saved link refers to an unknown experience");
    if (!finite({l.d_m(), l.heading_rad(), l.facing_rad(), l.travel_time_s()}) || l.d_m() < 0 ||
        l.travel_time_s() < 0) {
      Reject("saved link has invalid numbers");
    }
  };
  for (const auto& l : m.links()) check_link(l);
  const auto check_scan = [&](const proto::ScanLink& l) {
    check_link(l.link());
    if (!finite({l.walls_xx(), l.walls_xy(), l.walls_yy(), l.turn_x(), l.turn_y(), l.turn_turn()}))
      Reject("saved scan link's information is not finite");
  };
  for (const auto& l : m.scan_links()) check_scan(l);
  for (const auto& l : m.recent_scans()) check_scan(l);
  if (m.recent_scans_kept_size() > m.recent_scans_size()) Reject("saved registrations' flags outnumber them");
  if (m.has_turned_since_hold_rad() && !(m.turned_since_hold_rad() >= 0)) {
    Reject("saved turn since the last heading hold is not a number or negative");
  }
  if (m.outside_gate_offset_rad_size() != m.outside_gate_turned_rad_size() ||
      !std::all_of(m.outside_gate_offset_rad().begin(), m.outside_gate_offset_rad().end(),
                   [](double v) { return std::isfinite(v); }) ||
      !std::all_of(m.outside_gate_turned_rad().begin(), m.outside_gate_turned_rad().end(),
                   [](double v) { return v >= 0; }) ||
      (m.outside_gate_axis_size() != 0 && m.outside_gate_axis_size() != m.outside_gate_offset_rad_size()) ||
      !std::all_of(m.outside_gate_axis().begin(), m.outside_gate_axis().end(), [](uint32_t a) { return a <= 1; })) {
    Reject("saved wall offsets past the heading gate are not finite pairs, each with its axis (0 or 1)");
  }
  if (m.frames_since_graph() > static_cast<uint32_t>(std::numeric_limits<int>::max())) {
    Reject("saved frames since the least-squares correction out of range");
  }
  if (m.has_bridge()) {
    const proto::Bridge& b = m.bridge();
    if (b.from_id() >= std::max<uint32_t>(n, 1)) Reject("saved bridge starts at an unknown experience");
    if (!finite({b.x_m(), b.y_m(), b.time_s(), b.facing_offset_rad()}) || b.time_s() < 0) {
      Reject("saved bridge has invalid numbers");
    }
  }
  if (m.has_current() && m.current_id() >= n) Reject("saved current experience is unknown");
  if (!m.has_current() && n > 0) Reject("saved map has experiences but no current one");
  if (!finite({m.accum_x_m(), m.accum_y_m(), m.accum_facing_rad(), m.accum_time_s()})) {
    Reject("saved odometry accumulator is not finite");
  }
  if (!std::isfinite(m.manhattan_axes_rad()) ||
      !std::all_of(m.manhattan_window_rad().begin(), m.manhattan_window_rad().end(),
                   [](double d) { return std::isfinite(d); })) {
    Reject("saved wall axes or wall directions are not finite");
  }
  if (m.has_pose_cells_current() && m.pose_cells_current_id() >= n) Reject("saved pose-cell experience is unknown");
  if (!std::isfinite(m.driven_since_recognition_m()) || m.driven_since_recognition_m() < 0) {
    Reject("saved distance since the last recognition is not finite or negative");
  }
  if (m.sweep_experience() > n) Reject("saved sweep position out of range");
  for (uint32_t li : m.local_region_links()) {
    if (li >= nl) Reject("saved local region refers to an unknown link");
  }

  experiences_.clear();
  for (uint32_t i = 0; i < n; ++i) {
    const auto& p = m.experiences(i);
    experiences_.push_back({i, p.x_m(), p.y_m(), WrapAngle(p.th_rad()), p.template_id(), p.pc_x(), p.pc_y(), p.pc_th(),
                            p.has_wall_rad() ? std::optional(p.wall_rad()) : std::nullopt, {}});
    for (int k = 0; k + 1 < p.scan_xy_size(); k += 2) experiences_.back().scan.emplace_back(p.scan_xy(k), p.scan_xy(k + 1));
  }
  links_.clear();
  links_from_.assign(n, {});
  links_to_.assign(n, {});
  for (uint32_t i = 0; i < nl; ++i) {
    const auto& p = m.links(i);
    links_.push_back({p.from_id(), p.to_id(), p.d_m(), p.heading_rad(), p.facing_rad(), p.travel_time_s(),
                      std::max<uint32_t>(1, p.traversals()), p.closes_loop()});
    links_from_[p.from_id()].push_back(i);
    links_to_[p.to_id()].push_back(i);
  }
  scan_links_.clear();
  recent_scans_.clear();
  // A link saved before its turn was measured (turn entries zero) has its facing weighed as it
  // was then, by 1 / exp_graph_scan_sigma_rad^2.
  const double unmeasured_turn = config_.exp_graph_scan_sigma_m * config_.exp_graph_scan_sigma_m /
                                 (2 * config_.exp_graph_scan_sigma_rad * config_.exp_graph_scan_sigma_rad);
  const auto load_scan = [unmeasured_turn](const proto::ScanLink& p) {
    const proto::Link& l = p.link();
    ScanLink scan;
    scan.link = {l.from_id(), l.to_id(), l.d_m(), l.heading_rad(), l.facing_rad(), 0.0, 1, false};
    scan.information << p.walls_xx(), p.walls_xy(), p.turn_x(),  //
        p.walls_xy(), p.walls_yy(), p.turn_y(),                     //
        p.turn_x(), p.turn_y(), p.turn_turn();
    if (p.turn_turn() == 0) scan.information(2, 2) = unmeasured_turn;
    return scan;
  };
  for (const auto& p : m.scan_links()) scan_links_.push_back(load_scan(p));
  for (int k = 0; k < m.recent_scans_size(); ++k)
    recent_scans_.push_back({load_scan(m.recent_scans(k)), k < m.recent_scans_kept_size() && m.recent_scans_kept(k)});
  has_current_ = m.has_current();
  current_ = m.current_id();
  accum_x_ = m.accum_x_m();
  accum_y_ = m.accum_y_m();
  accum_facing_ = m.accum_facing_rad();
  accum_time_ = m.accum_time_s();
  sweep_experience_ = m.sweep_experience();
  sweep_link_ = m.sweep_link();
  local_region_.assign(m.local_region_links().begin(), m.local_region_links().end());
  next_sequence_ = m.next_sequence();
  manhattan_axes_ = m.has_manhattan_axes() ? std::optional(m.manhattan_axes_rad()) : std::nullopt;
  // The latest exp_manhattan_reference_frames of them (a config with a shorter window since).
  const int window = std::min(m.manhattan_window_rad_size(), config_.exp_manhattan_reference_frames);
  manhattan_window_.assign(m.manhattan_window_rad().end() - window, m.manhattan_window_rad().end());
  // An older file, without it: the gate wide open.
  turned_since_hold_rad_ =
      m.has_turned_since_hold_rad() ? m.turned_since_hold_rad() : std::numeric_limits<double>::max();
  offsets_outside_gate_.clear();
  for (int i = 0; i < m.outside_gate_offset_rad_size(); ++i)
    offsets_outside_gate_.push_back({m.outside_gate_offset_rad(i), m.outside_gate_turned_rad(i),
                                     m.outside_gate_axis_size() ? static_cast<int>(m.outside_gate_axis(i)) : 0});
  pose_cells_current_ = m.has_pose_cells_current() ? std::optional(m.pose_cells_current_id()) : std::nullopt;
  driven_since_recognition_m_ = m.driven_since_recognition_m();
  recaptured_since_recognition_ = m.recaptured_since_recognition();
  if (m.has_bridge()) {
    const proto::Bridge& b = m.bridge();
    bridge_from_ = b.from_id();
    bridge_x_ = b.x_m();
    bridge_y_ = b.y_m();
    bridge_time_ = b.time_s();
    bridge_facing_offset_ = b.facing_offset_rad();
    bridge_pending_ = b.pending();
  } else {
    StartBridge();
  }
  graph_pending_ = m.graph_pending();
  frames_since_graph_ = static_cast<int>(m.frames_since_graph());
  refused_recognitions_ = m.refused_recognitions();
  heading_recaptures_ = m.heading_recaptures();
  scan_registrations_ = m.scan_registrations();
  last_refusal_.reset();
}

}  // namespace rslam::experience_map
