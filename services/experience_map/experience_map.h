#pragma once
// The RatSLAM experience map (Milford & Wyeth, paper 000 section II; OpenRatSLAM
// experience_map.cpp is the reference behaviour).
//
// - Experiences are nodes with a pose p_i = (x, y, theta) in metres and radians.
// - A link i -> j stores the odometric transform of the transition, 000 eq. 1, in i's frame:
//   distance d, heading (direction of travel relative to theta_i), facing (theta_j - theta_i),
//   and the travel time.
// - Repeated transitions average the link (000 eq. 2): with n earlier observations,
//   dp_new = n/(n+1) dp_old + 1/(n+1) dp_curr (displacement averaged as a vector in i's frame,
//   facing as an angle), i.e. A = n/(n+1) I and B = 1/(n+1) I.
// - Map correction (000 eq. 3): each link pulls its two experiences towards agreement by alpha
//   (exp_correction = 0.5) of the error, positions and facings, in OpenRatSLAM's sweep order
//   (experience id, then its outgoing links).
//
// Bounded cost per frame (the design choice): OpenRatSLAM runs exp_loops full sweeps after every
// action, so its cost grows with the map. Here each frame gets exp_relax_budget_links link
// relaxations: first the links around the latest loop closure (a breadth-first region of up to
// exp_local_region_links links, re-swept every frame until it settles, which fixes most of the
// visible error at once), then the rest of the budget continues a global sweep from where the
// previous frame stopped. The global part executes exactly the link-relaxation sequence of
// repeated full sweeps, only sliced over frames, so with no new actions the map converges to the
// same fixed point as Relax(). Relax(iterations) runs full sweeps at once (e.g. before export).
// exp_relax_budget_links = 0 restores OpenRatSLAM's behaviour.
//
// exp_graph_optimisation replaces the relaxation by the least-squares correction of
// pose_graph.h: after a loop closure or a re-traversal, at most every exp_graph_period_frames
// frames, a few Gauss-Newton steps over the whole map (the first experience stays put).

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/math/angle.h"
#include "common/math/pose2d.h"
#include "services/experience_map/experience_action.h"
#include "services/experience_map/experience_map_config.h"
#include "services/experience_map/proto/experience_map.pb.h"

namespace rslam::experience_map {

struct Experience {
  uint32_t id = 0;
  double x_m = 0.0, y_m = 0.0, th_rad = 0.0;
  uint32_t template_id = 0;
  double pc_x = 0.0, pc_y = 0.0, pc_th = 0.0;
  // exp_manhattan: the walls' direction, modulo pi/2, relative to this experience's facing, as
  // first seen while the robot was at it (ExperienceMap::HoldHeading); the least-squares
  // correction holds the experience to the building's axes with it.
  std::optional<double> wall_rad;
  // exp_scan_links: the floor boundary seen while the robot was at it, in its frame (x forward,
  // y left), at most one point per exp_scan cell (ExperienceMap::ObserveBoundary).
  std::vector<Eigen::Vector2f> scan;

  Pose2D pose() const { return {x_m, y_m, th_rad}; }
};

struct Link {
  uint32_t from_id = 0, to_id = 0;
  double d_m = 0.0;
  double heading_rad = 0.0;
  double facing_rad = 0.0;
  double travel_time_s = 0.0;
  uint32_t traversals = 1;
  bool closes_loop = false;  // made by recognising a known place (kLink), not by a kCreate
  // `to`'s pose in `from`'s frame, as the link measures it.
  Pose2D pose() const { return {d_m * std::cos(heading_rad), d_m * std::sin(heading_rad), facing_rad}; }
};

// exp_scan_links: two stretches of the map whose walls were registered (scan_registration.h);
// never traversed, and not among the map's links. link: the newer experience's pose in the older's
// frame (from = older); information: what the registration measured of it, in the older's frame
// (ScanRegistration::information), which weighs it by direction: along a lone wall, or turned
// about a round table's centre, it says nothing. A link loaded from a file saved before the turn
// was measured has its facing weighed by exp_graph_scan_sigma_rad (ExperienceMap::Load).
struct ScanLink {
  Link link;
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
};

// What a least-squares correction (pose_graph.h) did.
struct PoseGraphResult {
  double largest_change = 0.0;  // over all steps (m or rad)
  int steps = 0;                // Gauss-Newton steps taken
  bool converged = false;       // the last step moved nothing by more than stop_below
};

// Why a recognition was refused: the gate (exp_recognition_max_jump_m with _jump_per_m,
// _max_turn_rad, _max_link_m), how far the recognition would have moved or turned the robot or
// how long its link would have been (m or rad), and the gate's limit then.
struct RecognitionRefusal {
  enum class Gate { kJump, kTurn, kLink };
  Gate gate = Gate::kJump;
  double value = 0.0;
  double limit = 0.0;
};
// One line for the log, naming the gate's key: "it would move the robot 5.10 m from where the map
// has it (exp_recognition_max_jump_m + _jump_per_m, at most _jump_cap_m: 4.30 m here)".
std::string ToString(const RecognitionRefusal& refusal);

// A pair of experiences known to be the same place when merging two maps.
struct MapAnchor {
  uint32_t this_id = 0;
  uint32_t other_id = 0;
};

class ExperienceMap {
 public:
  explicit ExperienceMap(const ExperienceMapConfig& config);
  ExperienceMap(const ExperienceMap&) = delete;
  ExperienceMap& operator=(const ExperienceMap&) = delete;

  // Accumulates odometry since the current experience (vtrans m/s, vrot rad/s over dt s).
  // Throws std::invalid_argument on non-finite values or negative dt.
  void Integrate(double vtrans_mps, double vrot_radps, double dt_s);

  // With exp_manhattan: this frame's wall direction in the robot frame, modulo 90 degrees (the
  // odometry's Velocity.wall_direction_rad; call it after Integrate for the frame that saw it).
  // The first exp_manhattan_reference_frames directions in a row, taken in the map frame, that
  // agree (resultant length of 4 x the angles at least 0.9) fix the building's axes; later ones
  // close enough to an axis (the gate of experience_map_config.h: exp_manhattan_min_offset_rad
  // after a held wall, widening as the robot turns, at most exp_manhattan_max_offset_rad) turn the
  // robot's heading exp_manhattan_gain of the way onto it. The first direction seen at an
  // experience is kept with it (Experience::wall_rad): with exp_graph_optimisation and
  // exp_manhattan_sigma_rad, the least-squares correction holds the experiences themselves to
  // the axes (pose_graph.h). Without exp_manhattan it does nothing.
  // Throws std::invalid_argument for a non-finite direction.
  void HoldHeading(double wall_direction_rad);
  // The building's axes (one direction modulo pi/2) in the map frame, once fixed.
  std::optional<double> manhattan_axes() const { return manhattan_axes_; }

  // With exp_scan_links: the frame's floor boundary (points in the robot frame, metres; call it
  // after Apply for the frame that saw it), kept with the current experience. Without it, or
  // before the first experience, it does nothing. Throws std::invalid_argument for a non-finite
  // point.
  void ObserveBoundary(std::span<const Eigen::Vector2f> points);
  // Scan links made so far (from the older experience to the newer: the newer's pose in the
  // older's frame), and the stretches registered to find them.
  const std::vector<ScanLink>& scan_links() const { return scan_links_; }
  uint64_t scan_registrations() const { return scan_registrations_; }

  // Applies one action, then spends this frame's correction budget (call it once per frame,
  // with kind kNone when the pose cells emitted nothing). Throws std::invalid_argument, with the
  // map unchanged, when ids are inconsistent: kCreate of an id other than the next dense id or
  // from an experience other than the current one; kLink/kSet of unknown ids or from an
  // experience other than the current one; non-finite angle or offset. A recognition too far
  // from where the map has the robot, or whose link would be too long, is refused
  // (exp_recognition_max_jump_m, _max_turn_rad, _max_link_m); until the next create or
  // recognition taken, actions from the refused experience (the pose cells' current) count as
  // from the current one.
  void Apply(const ExperienceAction& action);

  // Recognitions refused by the gates above so far, and the one the last Apply refused.
  uint64_t refused_recognitions() const { return refused_recognitions_; }
  const std::optional<RecognitionRefusal>& last_refusal() const { return last_refusal_; }
  // Headings taken back from past the heading hold's gate (exp_manhattan_recapture_frames).
  uint64_t heading_recaptures() const { return heading_recaptures_; }
  // After a refused recognition, the experience the pose cells take for current (the map keeps
  // its own, current_id()); actions from either are accepted until the next create or
  // recognition taken.
  std::optional<uint32_t> pose_cells_current() const { return pose_cells_current_; }

  // One frame's correction budget only (Apply calls it). Returns link relaxations done.
  int CorrectBudgeted();
  // Largest change (m or rad) one link relaxation made during the last Apply, CorrectBudgeted
  // or Relax call: 0 when the map did not move.
  double last_correction() const { return last_correction_; }
  // `iterations` full sweeps over all links (OpenRatSLAM iterate()); resets the sliced sweep to
  // a sweep boundary and drops the local region.
  void Relax(int iterations);
  // The least-squares correction of pose_graph.h (up to `iterations` Gauss-Newton steps, fewer
  // once a step moves nothing by more than stop_below) now, whatever exp_graph_optimisation
  // says; e.g. before export.
  PoseGraphResult OptimiseGraph(int iterations, double stop_below = 0.0);

  // Shortest path by travel time over links (either direction) from `from_id` to `goal_id`,
  // both included; empty when unreachable. Throws std::invalid_argument for unknown ids.
  std::vector<uint32_t> PathToGoal(uint32_t from_id, uint32_t goal_id) const;

  // Appends `other` (its ids offset by this map's experience count), optionally anchored: the
  // first anchor places other's experience on ours (rigid transform of other's poses) and every
  // anchor adds a zero-length link this_id -> other_id + offset. Current experience unchanged.
  void MergeFrom(const ExperienceMap& other, const std::vector<MapAnchor>& anchors);

  const std::vector<Experience>& experiences() const { return experiences_; }
  const std::vector<Link>& links() const { return links_; }
  bool has_current() const { return has_current_; }
  uint32_t current_id() const { return current_; }
  // Current experience's pose plus the odometry accumulated since it.
  Pose2D RobotPose() const;
  uint64_t next_sequence() const { return next_sequence_; }
  // Largest link error (position, m) over the map: how far from consistent the map is.
  double MaxLinkError() const;
  const ExperienceMapConfig& config() const { return config_; }

  // The whole state: a map loaded from it goes on exactly as this one would (scratch aside).
  proto::ExperienceMap Save() const;
  // Replaces the map; throws std::invalid_argument (map unchanged) when the message is
  // inconsistent (unknown ids, non-finite numbers).
  void Load(const proto::ExperienceMap& message);

 private:
  struct Observation {
    double d, heading, facing, time;
  };
  Observation ObservedFromCurrent(const ExperienceAction& a) const;
  // exp_bridge_recognitions: the robot in bridge_from_'s frame, by the odometry since it.
  Observation ObservedFromBridge() const;
  void AddLink(uint32_t from, uint32_t to, const Observation& o);
  void AverageInto(Link& link, const Observation& o, bool reversed);
  int FindLink(uint32_t from, uint32_t to) const;
  // Makes `id` current, the robot at the action's offset from it facing its relative angle.
  void SetCurrent(uint32_t id, const ExperienceAction& a);
  // exp_bridge_recognitions: the odometry from here on bridges from the current experience.
  void StartBridge();
  // Relaxes link links_[index] (000 eq. 3); returns the largest change it made.
  double RelaxLink(uint32_t index);
  void SeedLocalRegion(uint32_t a, uint32_t b);
  void ValidateIds(const ExperienceAction& a) const;
  // exp_recognition_max_jump_m, _max_turn_rad, _max_link_m: why the recognition `a` (kLink or
  // kSet, ids valid) whose link would be link_m long is refused, if it would move or turn the
  // robot too far from where the map has it, or link two places too far apart.
  std::optional<RecognitionRefusal> RefusalOf(const ExperienceAction& a, double link_m) const;
  // exp_scan_links: registers the stretch around experience `a` with the one around the nearest
  // old experience of each of the exp_scan_visits nearest visits in the map, and keeps a scan
  // link when they agree.
  void TryScanLink(uint32_t a);
  // ... one of those registrations: the stretch around `a` (its points `source`) with the one
  // around `older`.
  void RegisterStretch(uint32_t a, uint32_t older, const std::vector<Eigen::Vector2f>& source);
  // The distance the map has the robot driven since it made experience `since`.
  double DrivenSince(uint32_t since) const;
  // exp_scan_confirm_ids: the loop scan links a and b close with the map's placement of their ends
  // is within exp_scan_confirm_m / _rad.
  bool ScanLinksAgree(const ScanLink& a, const ScanLink& b) const;
  // The scan points of experiences [centre - exp_scan_region, centre + exp_scan_region] (those
  // below `end`), placed in centre's frame as the map has them, one per cell.
  std::vector<Eigen::Vector2f> StretchPoints(uint32_t centre, uint32_t end) const;
  // The map's current experience, or the pose cells' after a refused recognition.
  bool IsCurrent(uint32_t id) const { return id == current_ || pose_cells_current_ == id; }

  const ExperienceMapConfig config_;
  std::vector<Experience> experiences_;
  std::vector<Link> links_;
  std::vector<std::vector<uint32_t>> links_from_;  // per experience: outgoing link indices
  std::vector<std::vector<uint32_t>> links_to_;    // per experience: incoming link indices
  bool has_current_ = false;
  uint32_t current_ = 0;
  double accum_x_ = 0.0, accum_y_ = 0.0, accum_facing_ = 0.0, accum_time_ = 0.0;
  uint32_t sweep_experience_ = 0;  // global sliced sweep position
  uint32_t sweep_link_ = 0;
  std::vector<uint32_t> local_region_;  // link indices, breadth-first from the latest closure
  // SeedLocalRegion scratch (not state): per experience / link, the stamp of the last seed that
  // reached it, and the breadth-first queue.
  std::vector<uint32_t> seen_experience_;
  std::vector<uint32_t> seen_link_;
  uint32_t seed_stamp_ = 0;
  std::vector<uint32_t> seed_queue_;
  // RelaxLink scratch (not state): per link, the last angle (from's facing plus the link's
  // heading) and its cosine and sine; a NaN angle matches nothing.
  struct LinkTrig {
    double angle = std::numeric_limits<double>::quiet_NaN();
    double cos = 0.0;
    double sin = 0.0;
  };
  std::vector<LinkTrig> link_trig_;
  uint64_t next_sequence_ = 0;
  double last_correction_ = 0.0;
  // HoldHeading: the axes once fixed, and while fixing them the latest wall directions (map frame,
  // at most exp_manhattan_reference_frames).
  std::optional<double> manhattan_axes_;
  std::deque<double> manhattan_window_;
  // Turned (rad, summed absolute) since a wall direction last held the heading: widens the gate.
  // A map saved without it (an older file) loads with the gate wide open.
  double turned_since_hold_rad_ = 0.0;
  // exp_manhattan_recapture_frames: the wall directions' offsets from the axes since the last hold
  // (at most that many, the latest), each with turned_since_hold_rad_ when it came and the axis (0
  // or 1: which of the two perpendicular ones) it is off.
  struct OutsideGate {
    double offset_rad;
    double turned_rad;
    int axis;
  };
  std::deque<OutsideGate> offsets_outside_gate_;
  // exp_recognition_max_jump_m: metres driven since the last recognition taken (or the start).
  double driven_since_recognition_m_ = 0.0;
  bool moved_this_frame_ = false;  // the last Integrate moved or turned the robot
  // A heading recapture came since the last recognition of an older place: scan links do not
  // restart the distance above (exp_recognition_jump_scan_restarts).
  bool recaptured_since_recognition_ = false;
  std::optional<uint32_t> pose_cells_current_;
  uint64_t refused_recognitions_ = 0;
  std::optional<RecognitionRefusal> last_refusal_;
  uint64_t heading_recaptures_ = 0;
  std::vector<ScanLink> scan_links_;
  uint64_t scan_registrations_ = 0;
  // exp_scan_confirm_ids: the registrations made around the latest exp_scan_confirm_ids ids, each
  // kept or waiting for another to confirm it.
  struct RecentScan {
    ScanLink scan;
    bool kept = false;
  };
  std::vector<RecentScan> recent_scans_;
  // exp_bridge_recognitions: the experience made last (bridge_from_), the robot's odometry since
  // it in its frame as it was made (x, y, time), the robot's facing in that frame minus
  // accum_facing_ (only a recognition changes it), and whether a recognition was taken since. A
  // map saved without it (an older file) loads with a bridge started at its current experience.
  uint32_t bridge_from_ = 0;
  double bridge_x_ = 0.0, bridge_y_ = 0.0, bridge_time_ = 0.0, bridge_facing_offset_ = 0.0;
  bool bridge_pending_ = false;
  bool graph_pending_ = false;    // links changed since the last least-squares correction
  int frames_since_graph_ = 0;
};

}  // namespace rslam::experience_map
