#include "tools/eval/place_recognition_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

namespace rslam::eval {

std::vector<PlaceMatch> BestMatches(const DifferenceMatrix& differences,
                                    std::span<const int> true_reference, int tolerance,
                                    int rival_exclusion) {
  const Eigen::Index queries = differences.rows();
  const Eigen::Index references = differences.cols();
  if (queries == 0 || references == 0) {
    throw std::invalid_argument("difference matrix is empty (" + std::to_string(queries) + " x " +
                                std::to_string(references) + ")");
  }
  if (!differences.allFinite()) throw std::invalid_argument("difference matrix has NaN or inf entries");
  if (static_cast<Eigen::Index>(true_reference.size()) != queries) {
    throw std::invalid_argument("true_reference has " + std::to_string(true_reference.size()) +
                                " entries for " + std::to_string(queries) + " queries");
  }
  if (tolerance < 0) throw std::invalid_argument("tolerance must be >= 0");
  if (rival_exclusion < 0) rival_exclusion = tolerance;
  // A floor on the row spread so a flat row (all equal) gives a zero margin, not NaN.
  constexpr double kMinimumSpread = 1e-12;

  std::vector<PlaceMatch> matches;
  matches.reserve(static_cast<std::size_t>(queries));
  for (Eigen::Index i = 0; i < queries; ++i) {
    const int truth = true_reference[static_cast<std::size_t>(i)];
    if (truth < 0 || truth >= references) {
      throw std::invalid_argument("true reference " + std::to_string(truth) + " of query " +
                                  std::to_string(i) + " is out of range");
    }
    PlaceMatch m;
    m.query = static_cast<int>(i);
    m.true_reference = truth;
    Eigen::Index best = 0;
    m.best_difference = differences.row(i).minCoeff(&best);
    m.reference = static_cast<int>(best);
    m.second_best_difference = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < references; ++j) {
      if (std::abs(j - best) > rival_exclusion) {
        m.second_best_difference = std::min(m.second_best_difference, differences(i, j));
      }
    }
    const double mean = differences.row(i).mean();
    const double spread = std::sqrt((differences.row(i).array() - mean).square().mean());
    m.margin = (m.second_best_difference - m.best_difference) / std::max(spread, kMinimumSpread);
    m.correct = std::abs(m.reference - truth) <= tolerance;
    matches.push_back(m);
  }
  return matches;
}

std::vector<PlaceMatch> BestMatchesFrameAligned(const DifferenceMatrix& differences, int tolerance,
                                                int rival_exclusion) {
  std::vector<int> truth(static_cast<std::size_t>(differences.rows()));
  for (std::size_t i = 0; i < truth.size(); ++i) truth[i] = static_cast<int>(i);
  if (differences.rows() > differences.cols()) {
    throw std::invalid_argument("frame-aligned sets need at least as many references (" +
                                std::to_string(differences.cols()) + ") as queries (" +
                                std::to_string(differences.rows()) + ")");
  }
  return BestMatches(differences, truth, tolerance, rival_exclusion);
}

double RecallAtOne(std::span<const PlaceMatch> matches) {
  if (matches.empty()) return 0.0;
  const auto correct = std::count_if(matches.begin(), matches.end(), [](const PlaceMatch& m) { return m.correct; });
  return static_cast<double>(correct) / static_cast<double>(matches.size());
}

namespace {

// Accepts queries from the most confident down; a group of equal confidence goes in whole or
// not at all, because no threshold can separate it.
double LargestCorrectPrefix(std::span<const PlaceMatch> matches,
                            const std::function<double(const PlaceMatch&)>& confidence_cost) {
  if (matches.empty()) return 0.0;
  std::vector<const PlaceMatch*> order;
  order.reserve(matches.size());
  for (const PlaceMatch& m : matches) order.push_back(&m);
  std::stable_sort(order.begin(), order.end(), [&](const PlaceMatch* a, const PlaceMatch* b) {
    return confidence_cost(*a) < confidence_cost(*b);
  });
  std::size_t accepted = 0;
  std::size_t k = 0;
  while (k < order.size()) {
    std::size_t group_end = k;
    bool group_correct = true;
    const double cost = confidence_cost(*order[k]);
    while (group_end < order.size() && confidence_cost(*order[group_end]) == cost) {
      group_correct = group_correct && order[group_end]->correct;
      ++group_end;
    }
    if (!group_correct) break;
    accepted = group_end;
    k = group_end;
  }
  return static_cast<double>(accepted) / static_cast<double>(matches.size());
}

}  // namespace

double RecallAtFullPrecision(std::span<const PlaceMatch> matches) {
  return LargestCorrectPrefix(matches, [](const PlaceMatch& m) { return -m.margin; });
}

double RecallAtFullPrecisionByDifference(std::span<const PlaceMatch> matches) {
  return LargestCorrectPrefix(matches, [](const PlaceMatch& m) { return m.best_difference; });
}

}  // namespace rslam::eval
