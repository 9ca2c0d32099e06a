#include "tools/eval/sequence_matcher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rslam::eval {

namespace {

void RequireUsable(const DifferenceMatrix& differences) {
  if (differences.rows() == 0 || differences.cols() == 0) throw std::invalid_argument("difference matrix is empty");
  if (!differences.allFinite()) throw std::invalid_argument("difference matrix has NaN or inf entries");
}

}  // namespace

DifferenceMatrix LocalContrastEnhance(const DifferenceMatrix& differences, int window) {
  RequireUsable(differences);
  if (window < 3) throw std::invalid_argument("contrast window must be >= 3, got " + std::to_string(window));
  const Eigen::Index rows = differences.rows();
  const Eigen::Index cols = differences.cols();
  const Eigen::Index half = window / 2;
  // A floor on the spread so a flat window (all equal) does not divide by zero.
  constexpr double kMinimumSpread = 1e-9;
  DifferenceMatrix enhanced(rows, cols);
  Eigen::VectorXd sum(cols + 1), sum_sq(cols + 1);
  for (Eigen::Index i = 0; i < rows; ++i) {
    sum(0) = 0.0;
    sum_sq(0) = 0.0;
    for (Eigen::Index j = 0; j < cols; ++j) {
      sum(j + 1) = sum(j) + differences(i, j);
      sum_sq(j + 1) = sum_sq(j) + differences(i, j) * differences(i, j);
    }
    for (Eigen::Index j = 0; j < cols; ++j) {
      const Eigen::Index lo = std::max<Eigen::Index>(0, j - half);
      const Eigen::Index hi = std::min<Eigen::Index>(cols, j + half + 1);
      const double n = static_cast<double>(hi - lo);
      const double mean = (sum(hi) - sum(lo)) / n;
      const double variance = std::max(0.0, (sum_sq(hi) - sum_sq(lo)) / n - mean * mean);
      enhanced(i, j) = (differences(i, j) - mean) / std::max(std::sqrt(variance), kMinimumSpread);
    }
  }
  return enhanced;
}

DifferenceMatrix SequenceMatchDifferences(const DifferenceMatrix& differences,
                                          const SequenceMatchingOptions& options) {
  RequireUsable(differences);
  if (options.length < 1) throw std::invalid_argument("sequence length must be >= 1, got " + std::to_string(options.length));
  if (options.contrast_window != 0 && options.contrast_window < 3) {
    throw std::invalid_argument("contrast window must be 0 (off) or >= 3, got " + std::to_string(options.contrast_window));
  }
  const DifferenceMatrix d =
      options.contrast_window > 0 ? LocalContrastEnhance(differences, options.contrast_window) : differences;
  if (options.length == 1) return d;

  const Eigen::Index rows = d.rows();
  const Eigen::Index cols = d.cols();
  // Running sums along each diagonal: diagonal_sum(i, j) = sum_{k>=0} D(i-k, j-k).
  DifferenceMatrix diagonal_sum(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < cols; ++j) {
      diagonal_sum(i, j) = d(i, j) + (i > 0 && j > 0 ? diagonal_sum(i - 1, j - 1) : 0.0);
    }
  }
  const Eigen::Index length = options.length;
  DifferenceMatrix scores(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const Eigen::Index k = std::min(length, i + 1);
    const Eigen::Index first_candidate = std::min(k - 1, cols - 1);
    double worst = -std::numeric_limits<double>::infinity();
    for (Eigen::Index j = first_candidate; j < cols; ++j) {
      // Fewer references than frames in the sequence: use the diagonal that exists.
      const Eigen::Index terms = std::min(k, j + 1);
      const double before = (i - terms >= 0 && j - terms >= 0) ? diagonal_sum(i - terms, j - terms) : 0.0;
      scores(i, j) = (diagonal_sum(i, j) - before) / static_cast<double>(terms);
      worst = std::max(worst, scores(i, j));
    }
    for (Eigen::Index j = 0; j < first_candidate; ++j) scores(i, j) = worst;
  }
  return scores;
}

}  // namespace rslam::eval
