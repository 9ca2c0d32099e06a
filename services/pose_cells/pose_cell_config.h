#pragma once
// Configuration of the pose-cell network. Keys and defaults are OpenRatSLAM's (ratslam.ini
// names), so an OpenRatSLAM config section translates one to one.

#include <cmath>
#include <cstdint>

#include "common/config/config_error.h"

namespace rslam::pose_cells {

struct PoseCellConfig {
  int pc_dim_xy = 21;              // cells along x and y (St Lucia: 30)
  int pc_dim_th = 36;              // cells along theta
  int pc_w_e_dim = 7;              // excitation kernel width (cells, odd)
  double pc_w_e_var = 1.0;         // excitation Gaussian spread (cells)
  int pc_w_i_dim = 5;              // inhibition kernel width (cells, odd)
  double pc_w_i_var = 2.0;         // inhibition Gaussian spread (cells)
  double pc_global_inhib = 0.00002;
  double pc_cell_x_size = 1.0;     // metres per cell in x and y
  int pc_cells_to_avg = 3;         // half-width of the population-vector window around the peak
  double vt_active_decay = 1.0;
  double pc_vt_inject_energy = 0.15;
  double pc_vt_restore = 0.05;
  int vt_inject_min_age = 10;      // templates younger than this many templates inject nothing
  double exp_delta_pc_threshold = 2.0;  // pose-cell distance that makes a new experience
  // Not OpenRatSLAM's: a view of an experience made fewer than this many frames ago is not a
  // recognition (a new experience instead; 0: off). Turning back and forth on the spot, the robot
  // sees again views of a few seconds before; the link or set then takes its facing from the view
  // (coarse: 0.07-0.14 rad off the truth in one run) where the odometry over those frames is better.
  int exp_recognition_min_age_frames = 0;
  // Not OpenRatSLAM's: before a link to an experience made at least exp_boundary_min_age_frames
  // frames ago, register the floor boundary seen now with the one seen when it was made
  // (boundary_match.h); unless both hold exp_boundary_min_points points and register with a
  // median residual under exp_boundary_max_residual_m at an offset under
  // exp_boundary_max_offset_m, make a new experience instead. Needs the odometry's floor
  // boundary (odometry/velocity, floor_odometry); an experience or frame without one (adopted
  // from the map after a restart, a frame without odometry) is not checked. The service keeps
  // the boundaries only while the check, exp_boundary_offset or exp_submap_offset is on.
  bool exp_boundary_check = false;
  int exp_boundary_min_age_frames = 500;
  int exp_boundary_min_points = 8;
  double exp_boundary_max_residual_m = 0.05;
  double exp_boundary_max_offset_m = 0.7;
  // Not OpenRatSLAM's: a link or set to an experience whose floor boundary registers with the
  // view's as the check requires (whatever the experience's age) carries where the robot stands
  // in that experience's frame (Action::offset_x_m, offset_y_m); OpenRatSLAM puts the robot on it.
  bool exp_boundary_offset = false;
  // Not OpenRatSLAM's: a link or set carries where the robot stands in the recognised
  // experience's frame as measured from the views and the odometry. Of the last
  // exp_view_offset_frames frames, the one whose view matched its template with the smallest
  // difference is taken to stand where an experience of that template made within
  // exp_view_offset_max_gap_frames frames of the recognised one stood; the odometry from the
  // recognised experience to that one, then from that frame to now, gives the offset. Only
  // odometry over short stretches enters (the loop's drift cancels). A place is mostly recognised
  // after the robot passed it (the packet moves late): this says how far. Takes precedence over
  // exp_boundary_offset, which is used when no such frame is found.
  bool exp_view_offset = false;
  int exp_view_offset_frames = 80;
  int exp_view_offset_max_gap_frames = 100;
  // Not OpenRatSLAM's: a link or set to an experience made exp_submap_min_age_frames frames or
  // more before takes where the robot stands from the walls of both visits when they register
  // as exp_boundary_check requires (boundary_match.h): the floor boundaries of the experiences
  // made within exp_submap_frames frames of the recognised one, and those of the last
  // exp_submap_frames frames, each set placed by the odometry of its own visit. One frame's
  // boundary is a few metres of wall ahead, which slides along a corridor; thirty frames take in
  // the corners and openings that pin it (a corridor without any still lets it slide along).
  // Takes precedence over exp_view_offset, whose offset to an old place often puts the robot on
  // it (its best view is the frame that recognised it) however far beside it the robot drives
  // this time.
  bool exp_submap_offset = false;
  int exp_submap_min_age_frames = 150;
  int exp_submap_frames = 30;
  // Not OpenRatSLAM's: a new link to such a place whose two visits' walls register but do not
  // align as exp_boundary_check requires is refused (a new experience instead). A view and one
  // frame's few metres of wall can agree on a place that thirty frames of wall show is another.
  // Needs exp_submap_offset; a visit with too few boundary points is not checked.
  bool exp_submap_check = false;
  // Not OpenRatSLAM's: walls along the robot's way (a corridor) do not fix where along them the
  // robot stands, and the two visits' registration (boundary_match.h) then ends about where each
  // of its starts began, at residuals alike. With this at 1 or more, of the ends whose median
  // residual is at most this many times the best's, exp_submap_offset takes the one nearest to
  // the views' offset (exp_view_offset), else to the one frame's registered offset; 0 takes the
  // best. Needs exp_submap_offset.
  double exp_submap_alike_residual = 0.0;

  template <class V>
  void VisitFields(V& v) {
    v("pc_dim_xy", pc_dim_xy, "pose cells along x and y (OpenRatSLAM 21, St Lucia 30)");
    v("pc_dim_th", pc_dim_th, "pose cells along theta");
    v("pc_w_e_dim", pc_w_e_dim, "excitation kernel width in cells (odd)");
    v("pc_w_e_var", pc_w_e_var, "excitation Gaussian spread in cells");
    v("pc_w_i_dim", pc_w_i_dim, "inhibition kernel width in cells (odd)");
    v("pc_w_i_var", pc_w_i_var, "inhibition Gaussian spread in cells");
    v("pc_global_inhib", pc_global_inhib, "global inhibition subtracted from every cell per step");
    v("pc_cell_x_size", pc_cell_x_size, "metres per pose cell in x and y");
    v("pc_cells_to_avg", pc_cells_to_avg, "half-width of the population-vector window (cells)");
    v("vt_active_decay", vt_active_decay, "decay added each time the same view repeats");
    v("pc_vt_inject_energy", pc_vt_inject_energy, "energy a familiar view injects");
    v("pc_vt_restore", pc_vt_restore, "decay restored per view update");
    v("vt_inject_min_age", vt_inject_min_age,
      "a template injects only when at least this many templates were learnt after it");
    v("exp_delta_pc_threshold", exp_delta_pc_threshold,
      "pose-cell distance from the current experience that makes a new experience");
    v("exp_recognition_min_age_frames", exp_recognition_min_age_frames,
      "a view of an experience made fewer than this many frames ago is not a recognition (0: off)");
    v("exp_boundary_check", exp_boundary_check,
      "register the floor boundaries of the two views before linking to an old experience");
    v("exp_boundary_min_age_frames", exp_boundary_min_age_frames,
      "links to experiences made at least this many frames ago are checked");
    v("exp_boundary_min_points", exp_boundary_min_points,
      "a checked link needs this many boundary points in each view");
    v("exp_boundary_max_residual_m", exp_boundary_max_residual_m,
      "a checked link needs the registered boundaries' median residual under this (m)");
    v("exp_boundary_max_offset_m", exp_boundary_max_offset_m,
      "a checked link needs the registered offset between the two views under this (m)");
    v("exp_boundary_offset", exp_boundary_offset,
      "a link or set carries the robot's offset from the experience, from the registered floor boundaries");
    v("exp_view_offset", exp_view_offset,
      "a link or set carries the robot's offset from the experience, from the best view match of the last frames and the odometry");
    v("exp_view_offset_frames", exp_view_offset_frames,
      "exp_view_offset looks for the best view match in this many last frames");
    v("exp_view_offset_max_gap_frames", exp_view_offset_max_gap_frames,
      "exp_view_offset relates that view's experience to the recognised one only if made within this many frames of it");
    v("exp_submap_offset", exp_submap_offset,
      "a link or set to an old experience carries the offset that registers both visits' floor boundaries");
    v("exp_submap_min_age_frames", exp_submap_min_age_frames,
      "exp_submap_offset applies to experiences made at least this many frames ago");
    v("exp_submap_frames", exp_submap_frames,
      "exp_submap_offset registers the boundaries of this many frames around each visit");
    v("exp_submap_check", exp_submap_check,
      "refuse a new link to an old experience when both visits' floor boundaries register but do not align");
    v("exp_submap_alike_residual", exp_submap_alike_residual,
      "exp_submap_offset takes, of the registration's ends within this factor of the best residual, the one nearest the views' offset (0: the best)");
  }

  void Validate() const {
    Require(pc_dim_xy >= 3 && pc_dim_xy <= 1000, "pc_dim_xy", "must be in 3..1000");
    Require(pc_dim_th >= 3 && pc_dim_th <= 1000, "pc_dim_th", "must be in 3..1000");
    Require(pc_w_e_dim >= 1 && pc_w_e_dim % 2 == 1 && pc_w_e_dim <= pc_dim_xy && pc_w_e_dim <= pc_dim_th,
            "pc_w_e_dim", "must be odd, positive and no wider than the network");
    Require(pc_w_i_dim >= 1 && pc_w_i_dim % 2 == 1 && pc_w_i_dim <= pc_dim_xy && pc_w_i_dim <= pc_dim_th,
            "pc_w_i_dim", "must be odd, positive and no wider than the network");
    Require(pc_w_e_var > 0, "pc_w_e_var", "must be positive");
    Require(pc_w_i_var > 0, "pc_w_i_var", "must be positive");
    Require(pc_global_inhib >= 0 && pc_global_inhib < 1, "pc_global_inhib", "must be in [0, 1)");
    Require(pc_cell_x_size > 0, "pc_cell_x_size", "must be positive");
    Require(pc_cells_to_avg >= 0 && 2 * pc_cells_to_avg + 1 <= pc_dim_xy &&
                2 * pc_cells_to_avg + 1 <= pc_dim_th,
            "pc_cells_to_avg", "window must fit in the network");
    Require(vt_active_decay >= 0, "vt_active_decay", "must be non-negative");
    Require(pc_vt_inject_energy >= 0, "pc_vt_inject_energy", "must be non-negative");
    Require(pc_vt_restore >= 0, "pc_vt_restore", "must be non-negative");
    Require(vt_inject_min_age >= 0, "vt_inject_min_age", "must be non-negative");
    Require(exp_delta_pc_threshold > 0, "exp_delta_pc_threshold", "must be positive");
    Require(exp_boundary_min_age_frames >= 0, "exp_boundary_min_age_frames", "must be non-negative");
    Require(exp_recognition_min_age_frames >= 0, "exp_recognition_min_age_frames", "must be non-negative");
    Require(exp_boundary_min_points >= 3, "exp_boundary_min_points", "must be at least 3");
    Require(exp_boundary_max_residual_m > 0, "exp_boundary_max_residual_m", "must be positive");
    Require(exp_boundary_max_offset_m > 0, "exp_boundary_max_offset_m", "must be positive");
    Require(exp_view_offset_frames >= 1, "exp_view_offset_frames", "must be at least 1");
    Require(exp_view_offset_max_gap_frames >= 0, "exp_view_offset_max_gap_frames", "must be non-negative");
    Require(exp_submap_min_age_frames >= 0, "exp_submap_min_age_frames", "must be non-negative");
    Require(exp_submap_frames >= 0, "exp_submap_frames", "must be non-negative");
    Require(!exp_submap_check || exp_submap_offset, "exp_submap_check", "needs exp_submap_offset (the visits' walls)");
    Require(exp_submap_alike_residual == 0 || (exp_submap_alike_residual >= 1 && std::isfinite(exp_submap_alike_residual)),
            "exp_submap_alike_residual", "must be 0 or at least 1");
    Require(exp_submap_alike_residual == 0 || exp_submap_offset, "exp_submap_alike_residual",
            "needs exp_submap_offset (the visits' walls)");
  }
};

}  // namespace rslam::pose_cells
