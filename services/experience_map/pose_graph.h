#pragma once
// Least-squares correction of the experience map: the experiences' poses that best agree with
// every link at once, by Gauss-Newton on SE(2) with a sparse Cholesky solve (the pose-graph
// formulation of Grisetti et al., "A tutorial on graph-based SLAM", 2010).
//
// 000 eq. 3 (the relaxation of experience_map.h) moves each pair of experiences towards agreement
// with its link by alpha of the error, one link at a time. Its fixed point treats every link as
// equally sure, and an error around a long loop spreads only a few links per sweep. Here each
// link has an uncertainty (odometric links are much surer than a recognition's "the robot is at
// that experience", which is only as close as the pose-cell match radius), and the whole map
// moves to the minimum of
//     sum over links i->j of  |e_ij|^2 weighted by 1/sigma^2,
//     e_ij = ( R(theta_i)^T (p_j - p_i) - d_ij ,  theta_j - theta_i - facing_ij )
// where d_ij is the link's displacement in i's frame (000 eq. 1).
//
// The lowest-id experience of every connected part of the map stays where it is (the gauge: the
// map frame does not move, and merged maps without anchors stay apart).

#include <cmath>
#include <optional>
#include <vector>

#include "services/experience_map/experience_map.h"

namespace rslam::experience_map {

// Uncertainties (standard deviations) of the links' displacement (m) and facing (rad).
struct PoseGraphSigmas {
  double link_m, link_rad;        // odometric link
  double closure_m, closure_rad;  // link made by recognising a place
  double closure_robust_phi = 0;   // > 0: scale down closures and scan links that disagree (see pose_graph.cc)
  double scan_m = 1;               // scan link: its wall distances (the walls of two stretches registered)
};

// (1 - (r / limit)^2)^2 within the limit, 0 past it: 1 at r = 0, 0.56 at half the limit. A wall's
// pull with exp_manhattan_taper, on the robot and here.
inline double Taper(double r, double limit) {
  const double u = r / limit;
  return std::abs(u) >= 1 ? 0.0 : (1 - u * u) * (1 - u * u);
}

// The building's axes (exp_manhattan): an experience with a wall direction w (relative to its
// facing, modulo pi/2) adds the error r = theta + w - axes_rad (modulo pi/2) weighted by
// 1/sigma_rad^2, times Taper(r, max_offset_rad) with `taper`, while |r| <= max_offset_rad (farther
// off, the wall is taken for another one and the term is left out for that step).
struct ManhattanAxes {
  double axes_rad;
  double sigma_rad;
  double max_offset_rad;
  bool taper = false;
};

// Runs up to `iterations` Gauss-Newton steps over all experiences, links and scan links (the same
// error as a link's, weighted by 2 x information / scan_m^2, so only as far as the registration
// measured it), fewer when a step moves nothing by more than stop_below (m or rad). Links must
// name existing experiences.
PoseGraphResult OptimisePoseGraph(std::vector<Experience>& experiences, const std::vector<Link>& links,
                                  const std::vector<ScanLink>& scan_links,
                                  const PoseGraphSigmas& sigmas, int iterations, double stop_below = 0.0,
                                  const std::optional<ManhattanAxes>& manhattan = std::nullopt);

}  // namespace rslam::experience_map
