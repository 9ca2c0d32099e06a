#pragma once
// Configuration of the experience map. OpenRatSLAM keys keep their names and defaults.

#include <cmath>
#include <numbers>

#include "common/config/config_error.h"

namespace rslam::experience_map {

struct ExperienceMapConfig {
  int exp_loops = 10;               // full correction sweeps per Relax() call (OpenRatSLAM 10)
  double exp_correction = 0.5;      // alpha of 000 eq. 3
  double exp_initial_em_deg = 90.0; // facing of the first experience
  // Link relaxations per frame. 0 = OpenRatSLAM behaviour: exp_loops full sweeps after every
  // action (cost grows with the map).
  int exp_relax_budget_links = 1000;
  // Links around the latest loop closure re-relaxed every frame (part of the budget) until a
  // local sweep moves nothing by more than exp_relax_tolerance.
  int exp_local_region_links = 500;
  double exp_relax_tolerance = 1e-6;  // m and rad
  // Average the observed transform into an existing link when the robot re-traverses it
  // (000 eq. 2). OpenRatSLAM keeps the first observation only (false).
  bool exp_average_repeated_links = true;
  // On recognising an experience (a link, or a set with exp_set_view_angle), the share of the
  // difference between the dead-reckoned heading and the recognised one (the experience's facing
  // plus the view's offset) the robot's heading takes: 1 = OpenRatSLAM (the recognised heading),
  // 0 = keep dead reckoning.
  // A recognised heading is only as good as the view's shift match (about 1 degree a pixel) and
  // the experience's own facing; a blend keeps most of the drift correction and less noise.
  double exp_heading_correction = 1.0;
  // A transition to an experience already linked to the current one (a set, not a new link) takes
  // the view's offset angle as a recognition does (OpenRatSLAM: true), or takes its facing from
  // the map (false: the robot's heading and the re-traversed link's facing stay as the odometry
  // has them). Such a neighbour was mostly made a few frames before, its facing put there by the
  // same odometry; driving past a wall, the view's offset to it is parallax more than turn, often
  // the largest shift the template match searches, and at every set it turned the heading a
  // little further (0.5 rad in 100 frames of driving straight in one demo run).
  bool exp_set_view_angle = true;
  // On recognising an experience, the share of the way from the dead-reckoned position to the
  // experience's the robot's position takes; the rest stays as an offset from the experience
  // (it moves with the experience when the map is corrected). 1 = OpenRatSLAM (the robot is put
  // on the experience: each recognition adds the view's position tolerance, up to the pose-cell
  // match radius, to the map). The link's correction of the map is unchanged; below about 0.2
  // the map no longer holds together (a dead-reckoned robot keeps pulling it apart).
  double exp_position_correction = 1.0;
  // After a recognition, the next experience is linked from the last one made before it by the
  // odometry alone (its turns held by the walls as every link's are), not from the recognised
  // experience with the robot placed on it. The recognition's own link then carries where the
  // recognition put the robot, at a recognition's uncertainty; linked from the recognised
  // experience, its placement also went into the new experience's link, which is held as firmly
  // as odometry.
  bool exp_bridge_recognitions = false;
  // Least-squares correction (pose_graph.h) instead of the relaxation: when a link was closed or
  // re-traversed, at most every exp_graph_period_frames frames, exp_graph_iterations Gauss-Newton
  // steps over the whole map. Off = OpenRatSLAM's relaxation (the exp_loops, exp_correction and
  // exp_relax_* keys); on, those keys are not used.
  bool exp_graph_optimisation = false;
  int exp_graph_period_frames = 50;
  int exp_graph_iterations = 2;
  double exp_graph_link_sigma_m = 0.02;
  double exp_graph_link_sigma_rad = 0.002;
  double exp_graph_closure_sigma_m = 0.1;
  double exp_graph_closure_sigma_rad = 0.01;
  double exp_graph_closure_robust_phi = 0.0;  // 0: every recognition weighs by its sigmas alone
  // Not OpenRatSLAM's: a recognition (kLink or kSet) that would put the robot farther from
  // where the map has it than exp_recognition_max_jump_m, plus exp_recognition_jump_per_m for
  // each metre driven since the last recognition the map took, is refused: no link, the robot
  // stays where the map has it (and its next experience links from the map's current one). A
  // place seen twice looks alike (a corner, a stretch of wall) however far apart the two are;
  // the map, corrected at every recognition, knows the robot to within its drift since the last.
  // 0: every recognition is taken. Likewise one whose facing (the experience's plus the view's
  // relative angle; a kSet's only with exp_set_view_angle or after a refused recognition) is more
  // than exp_recognition_max_turn_rad from the robot's (0: any). Likewise a kLink whose link would
  // be longer than exp_recognition_max_link_m (0: any): a link that long joins two places, not one
  // seen again (the map measures such a link within 0.03-0.04 m of the truth in nine of ten; its
  // two wrong ones in 67 replayed runs were 0.81 and 1.04 m long, tools/demo/MEASUREMENTS.md
  // session 48).
  // A recognition of an experience within exp_recognition_jump_local_ids ids of the current one
  // (the stretch the robot is on, seen again a step back or ahead) says nothing of the drift, so
  // it does not restart the distance the jump gate grows with (0: every recognition taken does).
  // The allowance grows no further than exp_recognition_jump_cap_m (0: without bound): a run whose
  // recognitions are all of the stretch it is on drives on and on without restarting it, and then
  // a place 12 m away that looks alike was let through (tools/demo/MEASUREMENTS.md, session 54).
  double exp_recognition_max_jump_m = 0.0;
  double exp_recognition_jump_per_m = 0.0;
  double exp_recognition_jump_cap_m = 0.0;
  int exp_recognition_jump_local_ids = 0;
  // A scan link kept (below) ties the map at its newer end to a visit made long before, as a
  // recognition does: with this on, the distance the jump gate grows with restarts there too (at
  // the distance driven since that end), except between a heading recapture and the next
  // recognition of an older place.
  bool exp_recognition_jump_scan_restarts = false;
  double exp_recognition_max_turn_rad = 0.0;
  double exp_recognition_max_link_m = 0.0;
  // The robot's heading held to the building's walls (ExperienceMap::HoldHeading): most walls run
  // along two perpendicular directions (the Manhattan-world assumption). The first
  // exp_manhattan_reference_frames wall directions in a row that agree fix those axes in the map
  // frame; after that a wall direction close enough to an axis moves the robot's heading
  // exp_manhattan_gain of the way onto it (one farther off is another wall). Close enough: within
  // exp_manhattan_min_offset_rad right after a wall was held, a gate that widens by
  // exp_manhattan_offset_per_rad_turned for each radian the robot turns until the next one (the
  // odometry's heading drifts as the robot turns), up to exp_manhattan_max_offset_rad. A fixed
  // wide gate lets walls that are not on the axes turn the heading (a funnel's walls 0.29 rad
  // off, a round table's chords); a fixed narrow one never pulls back a heading that drifted past
  // it. Only the floor odometry (odometry.floor_odometry) reports wall directions; without it the
  // keys change nothing.
  bool exp_manhattan = false;
  int exp_manhattan_reference_frames = 50;
  double exp_manhattan_min_offset_rad = 0.25;
  double exp_manhattan_offset_per_rad_turned = 0.0;
  double exp_manhattan_max_offset_rad = 0.25;
  double exp_manhattan_gain = 0.2;
  // The pull of a wall, on the robot and in the least squares, weighed down as it nears the widest
  // gate, by (1 - (offset / exp_manhattan_max_offset_rad)^2)^2: a wall just inside it is more
  // likely one off the axes than the heading's drift.
  bool exp_manhattan_taper = false;
  // A heading that drifted past exp_manhattan_max_offset_rad, taken back when this many wall
  // directions in a row agree on the drift (ExperienceMap::HoldHeading has the rule). 0 = off.
  // With exp_manhattan_recapture_inside_widest, a heading past the gate of the moment as well.
  // With exp_manhattan_recapture_one_axis_turn_rad > 0, offsets that came over more turning than
  // that count only if walls of both axes gave some of them. With
  // exp_manhattan_recapture_moving_frames, only frames in which the robot moved or turned count:
  // a robot standing before one wall reads the same direction off the same image every frame.
  int exp_manhattan_recapture_frames = 0;
  double exp_manhattan_recapture_spread_rad = 0.05;
  double exp_manhattan_recapture_turn_rad = 1.0;
  double exp_manhattan_recapture_max_rad = 0.5;
  bool exp_manhattan_recapture_inside_widest = false;
  double exp_manhattan_recapture_one_axis_turn_rad = 0.0;
  bool exp_manhattan_recapture_moving_frames = false;
  // With exp_graph_optimisation: each experience's first wall direction holds its facing to the
  // axes in the least-squares correction with this uncertainty (0: only the robot is held). An
  // experience given its wall direction calls for a correction, as a closure does (at most one
  // every exp_graph_period_frames).
  double exp_manhattan_sigma_rad = 0.0;
  // Scan links (not OpenRatSLAM's; scan_registration.h), with exp_graph_optimisation: each
  // experience keeps the floor boundary seen while it was current (ExperienceMap::ObserveBoundary,
  // points within exp_scan_range_m of the robot). Once the robot has left experience a, and for
  // every exp_scan_every-th experience, the stretch of the map around a (the experiences within
  // exp_scan_region ids of it, placed as the map has them) is registered with the stretch around
  // the experience nearest to a in the map, if one made at least exp_scan_min_age experiences
  // before lies within exp_scan_radius_m. With exp_scan_visits > 1, the old experiences within
  // exp_scan_radius_m are taken as visits (split where their ids jump by more than twice
  // exp_scan_region, so their stretches do not overlap), and a is registered with the nearest
  // experience of each of the exp_scan_visits nearest visits: a stretch the map draws off (the
  // first, which can hang on one odometric link) is still tried where a later visit lies nearer
  // to a. A registration with exp_scan_min_pairs pairs, a median pair distance under
  // exp_scan_max_distance_m, exp_scan_min_inlier_share of a's points on the
  // other's walls, walls facing enough ways to fix the pose along them (exp_scan_min_weak_share)
  // and a correction of the map within exp_scan_max_correction_m / _rad becomes a link of its own
  // in the least squares, weighed by what the registration measured (exp_graph_scan_sigma_m,
  // pose_graph.h; the closures' robust kernel): the same walls seen on two visits are drawn in one
  // place whether or not a view recognised it. Scan links are never traversed, and are not among
  // the map's links.
  //
  // With exp_scan_confirm_ids > 0 a registration waits until another confirms it: one made
  // around an experience at most that many ids later (of any visit) whose measurement closes the
  // loop the two make with the map's placement of their ends within exp_scan_confirm_m / _rad. Right
  // registrations come in runs along a revisited wall and agree; a wall matched to its neighbour
  // stands alone. Once a run is confirmed each next registration that agrees with its last link
  // is kept at once.
  bool exp_scan_links = false;
  double exp_scan_range_m = 2.0;
  int exp_scan_region = 15;
  int exp_scan_every = 5;
  int exp_scan_min_age = 150;
  double exp_scan_radius_m = 1.0;
  int exp_scan_visits = 1;
  int exp_scan_min_pairs = 40;
  double exp_scan_max_distance_m = 0.03;
  double exp_scan_min_inlier_share = 0.5;
  double exp_scan_min_weak_share = 0.1;
  double exp_scan_max_correction_m = 0.5;
  double exp_scan_max_correction_rad = 0.2;
  int exp_scan_confirm_ids = 0;
  double exp_scan_confirm_m = 0.1;
  double exp_scan_confirm_rad = 0.05;
  double exp_graph_scan_sigma_m = 0.05;
  double exp_graph_scan_sigma_rad = 0.01;

  template <class V>
  void VisitFields(V& v) {
    v("exp_loops", exp_loops, "full correction sweeps per Relax() (and per action when the budget is 0)");
    v("exp_correction", exp_correction, "map correction rate alpha (000 eq. 3)");
    v("exp_initial_em_deg", exp_initial_em_deg, "facing of the first experience in degrees");
    v("exp_relax_budget_links", exp_relax_budget_links,
      "link relaxations per frame; 0 = OpenRatSLAM full relaxation after every action");
    v("exp_local_region_links", exp_local_region_links,
      "links around the latest loop closure relaxed first each frame");
    v("exp_relax_tolerance", exp_relax_tolerance,
      "local correction stops when a local sweep moves nothing more than this (m, rad)");
    v("exp_average_repeated_links", exp_average_repeated_links,
      "average re-traversals into the existing link (000 eq. 2)");
    v("exp_heading_correction", exp_heading_correction,
      "on recognition, the share of the heading difference taken from the experience (1 = OpenRatSLAM, 0 = none)");
    v("exp_set_view_angle", exp_set_view_angle,
      "a transition along an existing link (set) takes the view's offset angle (false: the map's facing)");
    v("exp_position_correction", exp_position_correction,
      "on recognition, the share of the way from the dead-reckoned position to the experience's (1 = OpenRatSLAM)");
    v("exp_bridge_recognitions", exp_bridge_recognitions,
      "after a recognition, link the next experience from the last one made, by odometry alone");
    v("exp_graph_optimisation", exp_graph_optimisation, "least-squares correction of the whole map after loop closures");
    v("exp_graph_period_frames", exp_graph_period_frames, "fewest frames between two least-squares corrections");
    v("exp_graph_iterations", exp_graph_iterations, "Gauss-Newton steps per least-squares correction");
    v("exp_graph_link_sigma_m", exp_graph_link_sigma_m, "uncertainty of an odometric link's position (m)");
    v("exp_graph_link_sigma_rad", exp_graph_link_sigma_rad, "uncertainty of an odometric link's facing (rad)");
    v("exp_graph_closure_sigma_m", exp_graph_closure_sigma_m, "uncertainty of a recognised place's position (m)");
    v("exp_graph_closure_sigma_rad", exp_graph_closure_sigma_rad, "uncertainty of a recognised place's facing (rad)");
    v("exp_graph_closure_robust_phi", exp_graph_closure_robust_phi,
      "> 0: recognitions far off the rest of the map (chi^2 >> phi) weigh less (dynamic covariance scaling)");
    v("exp_recognition_max_jump_m", exp_recognition_max_jump_m,
      "> 0: a recognition that would move the robot farther than this from where the map has it is refused (m)");
    v("exp_recognition_jump_per_m", exp_recognition_jump_per_m,
      "... plus this for each metre driven since the last recognition taken");
    v("exp_recognition_jump_cap_m", exp_recognition_jump_cap_m,
      "> 0: ... but never more than this in all (m; at least exp_recognition_max_jump_m)");
    v("exp_recognition_jump_local_ids", exp_recognition_jump_local_ids,
      "> 0: a recognition within this many ids of the current experience does not restart that distance");
    v("exp_recognition_jump_scan_restarts", exp_recognition_jump_scan_restarts,
      "a scan link kept restarts that distance too (at the distance driven since its newer end), "
      "except between a heading recapture and the next recognition");
    v("exp_recognition_max_turn_rad", exp_recognition_max_turn_rad,
      "> 0: a recognition that would turn the robot's facing by more than this is refused (rad)");
    v("exp_recognition_max_link_m", exp_recognition_max_link_m,
      "> 0: a recognition whose link would be longer than this is refused (m)");
    v("exp_manhattan", exp_manhattan, "hold the robot's heading to the walls' two perpendicular directions");
    v("exp_manhattan_reference_frames", exp_manhattan_reference_frames, "wall directions in a row that, agreeing, fix the axes");
    v("exp_manhattan_min_offset_rad", exp_manhattan_min_offset_rad,
      "right after a wall was held, a wall direction farther than this from an axis is another wall and is ignored (rad)");
    v("exp_manhattan_offset_per_rad_turned", exp_manhattan_offset_per_rad_turned,
      "... a gate that widens by this for each radian turned until a wall is held again");
    v("exp_manhattan_max_offset_rad", exp_manhattan_max_offset_rad,
      "... up to this; the least-squares correction's gate for the experiences' walls (rad)");
    v("exp_manhattan_gain", exp_manhattan_gain, "share of a wall direction's offset from its axis taken out per frame");
    v("exp_manhattan_taper", exp_manhattan_taper, "weigh a wall's pull down as its offset nears exp_manhattan_max_offset_rad");
    v("exp_manhattan_recapture_frames", exp_manhattan_recapture_frames,
      "wall directions past the gate that, agreeing, are taken for the heading's drift and taken out "
      "at once (0 = off)");
    v("exp_manhattan_recapture_spread_rad", exp_manhattan_recapture_spread_rad,
      "how far those may lie from their mean (rad)");
    v("exp_manhattan_recapture_turn_rad", exp_manhattan_recapture_turn_rad,
      "how far the robot must have turned while they came (rad)");
    v("exp_manhattan_recapture_max_rad", exp_manhattan_recapture_max_rad,
      "the largest drift taken out so (rad)");
    v("exp_manhattan_recapture_inside_widest", exp_manhattan_recapture_inside_widest,
      "wall directions past the gate of the moment count toward a recapture, not only those past the widest");
    v("exp_manhattan_recapture_one_axis_turn_rad", exp_manhattan_recapture_one_axis_turn_rad,
      "> 0: offsets that came over more turning than this recapture only if walls of both axes gave "
      "at least two of them (rad)");
    v("exp_manhattan_recapture_moving_frames", exp_manhattan_recapture_moving_frames,
      "only wall directions of frames in which the robot moved or turned count toward a recapture");
    v("exp_manhattan_sigma_rad", exp_manhattan_sigma_rad,
      "> 0, with exp_graph_optimisation: uncertainty of the experiences' wall directions in the least-squares correction (rad)");
    v("exp_scan_links", exp_scan_links,
      "with exp_graph_optimisation: register stretches of the map that see the same walls and tie them by a link");
    v("exp_scan_range_m", exp_scan_range_m, "floor-boundary points farther than this from the robot are not kept (m)");
    v("exp_scan_region", exp_scan_region, "a stretch of the map: the experiences within this many ids of its centre");
    v("exp_scan_every", exp_scan_every, "register the stretch around every this-many-th experience");
    v("exp_scan_min_age", exp_scan_min_age, "... with one whose centre was made at least this many experiences before");
    v("exp_scan_radius_m", exp_scan_radius_m, "... and lies within this distance in the map (m)");
    v("exp_scan_visits", exp_scan_visits,
      "... with the nearest experience of each of this many earlier visits nearest to it");
    v("exp_scan_min_pairs", exp_scan_min_pairs, "a registration needs this many point pairs");
    v("exp_scan_max_distance_m", exp_scan_max_distance_m, "... their median distance under this (m)");
    v("exp_scan_min_inlier_share", exp_scan_min_inlier_share,
      "... this share of the newer stretch's points within two cells of the older's");
    v("exp_scan_min_weak_share", exp_scan_min_weak_share,
      "... walls facing enough ways to fix the pose along them (0: one straight wall, 0.5: every way)");
    v("exp_scan_max_correction_m", exp_scan_max_correction_m, "... and a move of the map's guess within this (m)");
    v("exp_scan_max_correction_rad", exp_scan_max_correction_rad, "... and a turn within this (rad)");
    v("exp_scan_confirm_ids", exp_scan_confirm_ids,
      "> 0: a registration is kept once another around an experience at most this many ids later agrees with it");
    v("exp_scan_confirm_m", exp_scan_confirm_m, "... closing the loop of the two and the map within this (m)");
    v("exp_scan_confirm_rad", exp_scan_confirm_rad, "... and this (rad)");
    v("exp_graph_scan_sigma_m", exp_graph_scan_sigma_m,
      "uncertainty of a scan link's wall distances (m): weighted by 2 x its registration's information / this^2");
    v("exp_graph_scan_sigma_rad", exp_graph_scan_sigma_rad,
      "uncertainty of the facing of a scan link saved without its turn measured (rad)");
  }

  void Validate() const {
    Require(exp_loops >= 0, "exp_loops", "must be non-negative");
    Require(exp_correction > 0 && exp_correction <= 0.5, "exp_correction", "must be in (0, 0.5]");
    Require(exp_initial_em_deg >= -360 && exp_initial_em_deg <= 360, "exp_initial_em_deg",
            "must be in [-360, 360]");
    Require(exp_relax_budget_links >= 0, "exp_relax_budget_links", "must be non-negative");
    Require(exp_local_region_links >= 0, "exp_local_region_links", "must be non-negative");
    Require(exp_relax_tolerance >= 0, "exp_relax_tolerance", "must be non-negative");
    Require(exp_heading_correction >= 0 && exp_heading_correction <= 1, "exp_heading_correction", "must be in [0, 1]");
    Require(exp_position_correction > 0 && exp_position_correction <= 1, "exp_position_correction", "must be in (0, 1]");
    Require(exp_graph_period_frames >= 1, "exp_graph_period_frames", "must be at least 1");
    Require(exp_graph_iterations >= 1, "exp_graph_iterations", "must be at least 1");
    Require(exp_graph_link_sigma_m > 0, "exp_graph_link_sigma_m", "must be positive");
    Require(exp_graph_link_sigma_rad > 0, "exp_graph_link_sigma_rad", "must be positive");
    Require(exp_graph_closure_sigma_m > 0, "exp_graph_closure_sigma_m", "must be positive");
    Require(exp_graph_closure_sigma_rad > 0, "exp_graph_closure_sigma_rad", "must be positive");
    Require(std::isfinite(exp_graph_closure_robust_phi) && exp_graph_closure_robust_phi >= 0,
            "exp_graph_closure_robust_phi", "must be >= 0");
    Require(std::isfinite(exp_recognition_max_jump_m) && exp_recognition_max_jump_m >= 0,
            "exp_recognition_max_jump_m", "must be >= 0");
    Require(std::isfinite(exp_recognition_jump_per_m) && exp_recognition_jump_per_m >= 0,
            "exp_recognition_jump_per_m", "must be >= 0");
    Require(std::isfinite(exp_recognition_jump_cap_m) &&
                (exp_recognition_jump_cap_m == 0 || exp_recognition_jump_cap_m >= exp_recognition_max_jump_m),
            "exp_recognition_jump_cap_m", "must be 0 (no cap) or >= exp_recognition_max_jump_m");
    Require(exp_recognition_jump_local_ids >= 0, "exp_recognition_jump_local_ids", "must be >= 0");
    Require(std::isfinite(exp_recognition_max_turn_rad) && exp_recognition_max_turn_rad >= 0 &&
                exp_recognition_max_turn_rad <= std::numbers::pi,
            "exp_recognition_max_turn_rad", "must be in [0, pi]");
    Require(std::isfinite(exp_recognition_max_link_m) && exp_recognition_max_link_m >= 0,
            "exp_recognition_max_link_m", "must be >= 0");
    Require(exp_manhattan_reference_frames >= 1, "exp_manhattan_reference_frames", "must be at least 1");
    Require(std::isfinite(exp_manhattan_max_offset_rad) && exp_manhattan_max_offset_rad > 0 &&
                exp_manhattan_max_offset_rad < std::numbers::pi / 4,
            "exp_manhattan_max_offset_rad", "must be in (0, pi/4)");
    Require(std::isfinite(exp_manhattan_min_offset_rad) && exp_manhattan_min_offset_rad > 0,
            "exp_manhattan_min_offset_rad", "must be positive");
    Require(std::isfinite(exp_manhattan_offset_per_rad_turned) && exp_manhattan_offset_per_rad_turned >= 0,
            "exp_manhattan_offset_per_rad_turned", "must be >= 0");
    Require(exp_manhattan_recapture_frames >= 0 && exp_manhattan_recapture_frames <= 100000,
            "exp_manhattan_recapture_frames", "must be 0..100000");
    Require(std::isfinite(exp_manhattan_recapture_spread_rad) && exp_manhattan_recapture_spread_rad > 0 &&
                exp_manhattan_recapture_spread_rad < M_PI / 4,
            "exp_manhattan_recapture_spread_rad", "must be in (0, pi/4)");
    Require(std::isfinite(exp_manhattan_recapture_turn_rad) && exp_manhattan_recapture_turn_rad >= 0,
            "exp_manhattan_recapture_turn_rad", "must be >= 0");
    Require(std::isfinite(exp_manhattan_recapture_max_rad) && exp_manhattan_recapture_max_rad > 0 &&
                exp_manhattan_recapture_max_rad < M_PI / 4,
            "exp_manhattan_recapture_max_rad", "must be in (0, pi/4)");
    Require(std::isfinite(exp_manhattan_recapture_one_axis_turn_rad) && exp_manhattan_recapture_one_axis_turn_rad >= 0,
            "exp_manhattan_recapture_one_axis_turn_rad", "must be >= 0");
    Require(std::isfinite(exp_manhattan_gain) && exp_manhattan_gain > 0 && exp_manhattan_gain <= 1,
            "exp_manhattan_gain", "must be in (0, 1]");
    Require(std::isfinite(exp_manhattan_sigma_rad) && exp_manhattan_sigma_rad >= 0, "exp_manhattan_sigma_rad",
            "must be >= 0");
    Require(std::isfinite(exp_scan_range_m) && exp_scan_range_m > 0, "exp_scan_range_m", "must be positive");
    Require(exp_scan_region >= 1 && exp_scan_region <= 1000, "exp_scan_region", "must be 1..1000");
    Require(exp_scan_every >= 1, "exp_scan_every", "must be at least 1");
    Require(exp_scan_min_age > 2 * exp_scan_region, "exp_scan_min_age",
            "must exceed twice exp_scan_region (the two stretches must not overlap)");
    Require(std::isfinite(exp_scan_radius_m) && exp_scan_radius_m > 0, "exp_scan_radius_m", "must be positive");
    Require(exp_scan_visits >= 1, "exp_scan_visits", "must be at least 1");
    Require(exp_scan_min_pairs >= 3, "exp_scan_min_pairs", "must be at least 3");
    Require(std::isfinite(exp_scan_max_distance_m) && exp_scan_max_distance_m > 0, "exp_scan_max_distance_m",
            "must be positive");
    Require(std::isfinite(exp_scan_min_inlier_share) && exp_scan_min_inlier_share >= 0 && exp_scan_min_inlier_share <= 1,
            "exp_scan_min_inlier_share", "must be in [0, 1]");
    Require(std::isfinite(exp_scan_min_weak_share) && exp_scan_min_weak_share >= 0 && exp_scan_min_weak_share <= 0.5,
            "exp_scan_min_weak_share", "must be in [0, 0.5]");
    Require(std::isfinite(exp_scan_max_correction_m) && exp_scan_max_correction_m > 0, "exp_scan_max_correction_m",
            "must be positive");
    Require(std::isfinite(exp_scan_max_correction_rad) && exp_scan_max_correction_rad > 0,
            "exp_scan_max_correction_rad", "must be positive");
    Require(exp_scan_confirm_ids >= 0, "exp_scan_confirm_ids", "must be non-negative");
    Require(std::isfinite(exp_scan_confirm_m) && exp_scan_confirm_m > 0, "exp_scan_confirm_m", "must be positive");
    Require(std::isfinite(exp_scan_confirm_rad) && exp_scan_confirm_rad > 0, "exp_scan_confirm_rad", "must be positive");
    Require(exp_graph_scan_sigma_m > 0, "exp_graph_scan_sigma_m", "must be positive");
    Require(exp_graph_scan_sigma_rad > 0, "exp_graph_scan_sigma_rad", "must be positive");
  }
};

}  // namespace rslam::experience_map
