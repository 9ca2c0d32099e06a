#include "services/experience_map/pose_graph.h"

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <numbers>
#include <numeric>

namespace rslam::experience_map {
namespace {

// Index of each experience's variables in the system (3 per free experience), or -1 for the
// lowest-id experience of each connected part, which stays where it is.
std::vector<int> FreeIndices(size_t n, std::initializer_list<const std::vector<Link>*> link_sets) {
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0U);
  auto root = [&](uint32_t e) {
    while (parent[e] != e) e = parent[e] = parent[parent[e]];
    return e;
  };
  for (const std::vector<Link>* links : link_sets)
    for (const Link& l : *links) {
      const uint32_t a = root(l.from_id), b = root(l.to_id);
      parent[std::max(a, b)] = std::min(a, b);  // the root of a part is its lowest id
    }
  std::vector<int> index(n, -1);
  int next = 0;
  for (uint32_t e = 0; e < n; ++e) {
    if (root(e) != e) index[e] = 3 * next++;
  }
  return index;
}

}  // namespace

PoseGraphResult OptimisePoseGraph(std::vector<Experience>& experiences, const std::vector<Link>& links,
                                  const std::vector<ScanLink>& scan_links, const PoseGraphSigmas& sigmas,
                                  int iterations, double stop_below, const std::optional<ManhattanAxes>& manhattan) {
  std::vector<Link> scan_link_ends;
  for (const ScanLink& l : scan_links) scan_link_ends.push_back(l.link);
  const std::vector<int> index = FreeIndices(experiences.size(), {&links, &scan_link_ends});
  const int size = static_cast<int>(3 * std::count_if(index.begin(), index.end(), [](int i) { return i >= 0; }));
  PoseGraphResult result;
  if (size == 0) {
    result.converged = true;
    return result;
  }
  const Eigen::Vector3d link_weight(1 / (sigmas.link_m * sigmas.link_m), 1 / (sigmas.link_m * sigmas.link_m),
                                    1 / (sigmas.link_rad * sigmas.link_rad));
  const Eigen::Vector3d closure_weight(1 / (sigmas.closure_m * sigmas.closure_m),
                                       1 / (sigmas.closure_m * sigmas.closure_m),
                                       1 / (sigmas.closure_rad * sigmas.closure_rad));
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    triplets.clear();
    triplets.reserve((links.size() + scan_links.size()) * 36);
    Eigen::VectorXd gradient = Eigen::VectorXd::Zero(size);
    // weight: an Eigen::DiagonalMatrix (links) or a full Eigen::Matrix3d (scan links), in from's frame.
    const auto add_link = [&](const Link& l, auto weight, double robust_phi) {
      const Experience& from = experiences[l.from_id];
      const Experience& to = experiences[l.to_id];
      const double c = std::cos(from.th_rad), s = std::sin(from.th_rad);
      const double px = to.x_m - from.x_m, py = to.y_m - from.y_m;
      const Eigen::Vector3d error(c * px + s * py - l.d_m * std::cos(l.heading_rad),
                                  -s * px + c * py - l.d_m * std::sin(l.heading_rad),
                                  WrapAngle(to.th_rad - from.th_rad - l.facing_rad));
      Eigen::Matrix3d jf, jt;  // d error / d (x, y, theta) of from and of to
      jf << -c, -s, -s * px + c * py,  //
          s, -c, -c * px - s * py,     //
          0, 0, -1;
      jt << c, s, 0,  //
          -s, c, 0,   //
          0, 0, 1;
      // Dynamic covariance scaling (Agarwal et al., ICRA 2013): a recognition that disagrees with
      // the rest of the map by far more than its uncertainty (a wrong loop closure) pulls on it
      // with a weight scaled by s^2, s = min(1, 2 phi / (phi + chi^2)).
      if (robust_phi > 0) {
        const double chi2 = error.dot(weight * error);
        const double scale = std::min(1.0, 2 * robust_phi / (robust_phi + chi2));
        weight = weight * (scale * scale);
      }
      const int at[2] = {index[l.from_id], index[l.to_id]};
      const Eigen::Matrix3d* j[2] = {&jf, &jt};
      for (int a = 0; a < 2; ++a) {
        if (at[a] < 0) continue;
        gradient.segment<3>(at[a]) += j[a]->transpose() * (weight * error);
        for (int b = 0; b < 2; ++b) {
          if (at[b] < 0) continue;
          const Eigen::Matrix3d block = j[a]->transpose() * weight * *j[b];
          for (int r = 0; r < 3; ++r) {
            for (int q = 0; q < 3; ++q) triplets.emplace_back(at[a] + r, at[b] + q, block(r, q));
          }
        }
      }
    };
    for (const Link& l : links) {
      add_link(l, Eigen::DiagonalMatrix<double, 3>(l.closes_loop ? closure_weight : link_weight),
               l.closes_loop ? sigmas.closure_robust_phi : 0.0);
    }
    for (const ScanLink& l : scan_links) {
      // As the registration measured it (its position block is I / 2 for walls facing every way).
      add_link(l.link, Eigen::Matrix3d(2 * l.information / (sigmas.scan_m * sigmas.scan_m)), sigmas.closure_robust_phi);
    }
    if (manhattan) {
      // A unary term on theta: every free experience has a theta diagonal entry from its links,
      // so the pattern stays the one analysed at the first step.
      const double weight = 1 / (manhattan->sigma_rad * manhattan->sigma_rad);
      for (size_t e = 0; e < experiences.size(); ++e) {
        if (index[e] < 0 || !experiences[e].wall_rad) continue;
        const double error =
            std::remainder(experiences[e].th_rad + *experiences[e].wall_rad - manhattan->axes_rad, std::numbers::pi / 2);
        if (std::abs(error) > manhattan->max_offset_rad) continue;
        const double w = manhattan->taper ? weight * Taper(error, manhattan->max_offset_rad) : weight;
        gradient[index[e] + 2] += w * error;
        triplets.emplace_back(index[e] + 2, index[e] + 2, w);
      }
    }
    Eigen::SparseMatrix<double> hessian(size, size);
    hessian.setFromTriplets(triplets.begin(), triplets.end());
    if (iteration == 0) solver.analyzePattern(hessian);  // the same links every iteration
    solver.factorize(hessian);
    if (solver.info() != Eigen::Success) break;  // cannot happen with every part anchored
    const Eigen::VectorXd step = solver.solve(-gradient);
    double moved = 0.0;
    for (size_t e = 0; e < experiences.size(); ++e) {
      if (index[e] < 0) continue;
      const Eigen::Vector3d d = step.segment<3>(index[e]);
      Experience& x = experiences[e];
      x.x_m += d[0];
      x.y_m += d[1];
      x.th_rad = WrapAngle(x.th_rad + d[2]);
      moved = std::max({moved, std::abs(d[0]), std::abs(d[1]), std::abs(d[2])});
    }
    result.largest_change = std::max(result.largest_change, moved);
    ++result.steps;
    if (moved <= stop_below) {
      result.converged = true;
      break;
    }
  }
  return result;
}

}  // namespace rslam::experience_map
