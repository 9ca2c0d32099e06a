#include "tools/eval/place_recognition_metrics.h"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

#include "tools/eval/vpr_evaluation.h"

namespace rslam::eval {
namespace {

// Differences 1 everywhere except the chosen best reference of each query.
DifferenceMatrix WithBest(int queries, int references, const std::vector<std::pair<int, double>>& best) {
  DifferenceMatrix d = DifferenceMatrix::Constant(queries, references, 1.0);
  for (int i = 0; i < queries; ++i) d(i, best[static_cast<std::size_t>(i)].first) = best[static_cast<std::size_t>(i)].second;
  return d;
}

TEST(PlaceRecognitionMetrics, RecallAtOneCountsBestMatchesWithinTolerance) {
  // Queries 0..4; best references 0 (exact), 3 (off by 2), 5 (off by 3), 3 (exact), 0 (off by 4).
  const DifferenceMatrix d = WithBest(5, 8, {{0, 0.1}, {3, 0.1}, {5, 0.1}, {3, 0.1}, {0, 0.1}});
  EXPECT_DOUBLE_EQ(RecallAtOne(BestMatchesFrameAligned(d, 0)), 2.0 / 5.0);
  EXPECT_DOUBLE_EQ(RecallAtOne(BestMatchesFrameAligned(d, 2)), 3.0 / 5.0);
  EXPECT_DOUBLE_EQ(RecallAtOne(BestMatchesFrameAligned(d, 3)), 4.0 / 5.0);
  EXPECT_DOUBLE_EQ(RecallAtOne(BestMatchesFrameAligned(d, 4)), 1.0);
}

TEST(PlaceRecognitionMetrics, RecallAtFullPrecisionStopsAtTheMostConfidentWrongMatch) {
  // Each row: best difference b at the chosen reference, 1 elsewhere, so margin grows as b falls.
  // Confidence order (most first): q0 (b=0.1, correct), q1 (0.2, correct), q2 (0.3, wrong),
  // q3 (0.4, correct), q4 (0.5, correct), q5 (0.6, wrong): only q0 and q1 can be accepted.
  const DifferenceMatrix d = WithBest(6, 12, {{0, 0.1}, {1, 0.2}, {9, 0.3}, {3, 0.4}, {4, 0.5}, {0, 0.6}});
  const auto matches = BestMatchesFrameAligned(d, 0);
  EXPECT_DOUBLE_EQ(RecallAtOne(matches), 4.0 / 6.0);
  EXPECT_DOUBLE_EQ(RecallAtFullPrecision(matches), 2.0 / 6.0);
  EXPECT_DOUBLE_EQ(RecallAtFullPrecisionByDifference(matches), 2.0 / 6.0);
}

TEST(PlaceRecognitionMetrics, RecallAtFullPrecisionUsesTheMarginNotTheRawDifference) {
  // q0 is correct with a low best difference but a rival just as low: low margin. q1 is correct
  // and distinctive; q2 is wrong with a higher best difference than q0 yet a middling margin.
  DifferenceMatrix d = DifferenceMatrix::Constant(3, 10, 1.0);
  d(0, 0) = 0.10;
  d(0, 7) = 0.11;  // rival of q0
  d(1, 1) = 0.20;
  d(2, 8) = 0.30;  // q2's wrong best
  const auto matches = BestMatchesFrameAligned(d, 1);
  EXPECT_DOUBLE_EQ(RecallAtFullPrecision(matches), 1.0 / 3.0);             // q1 only
  EXPECT_DOUBLE_EQ(RecallAtFullPrecisionByDifference(matches), 2.0 / 3.0); // q0, q1
}

TEST(PlaceRecognitionMetrics, EqualConfidenceGroupIsRefusedWholeWhenOneIsWrong) {
  // Rows are permutations of one another with exactly representable statistics, so the two
  // margins are bit-identical.
  const DifferenceMatrix d = WithBest(2, 4, {{0, 0.5}, {3, 0.5}});
  EXPECT_DOUBLE_EQ(RecallAtFullPrecision(BestMatchesFrameAligned(d, 0)), 0.0);
}

TEST(PlaceRecognitionMetrics, RivalsInsideTheToleranceWindowDoNotLowerConfidence) {
  DifferenceMatrix d = DifferenceMatrix::Constant(1, 10, 1.0);
  d(0, 0) = 0.1;
  d(0, 1) = 0.1001;  // the neighbour looks alike, as neighbours do
  const auto within = BestMatchesFrameAligned(d, 2);
  EXPECT_DOUBLE_EQ(within[0].second_best_difference, 1.0);
  const auto exact = BestMatchesFrameAligned(d, 0);
  EXPECT_DOUBLE_EQ(exact[0].second_best_difference, 0.1001);
  EXPECT_GT(within[0].margin, exact[0].margin);
}

TEST(PlaceRecognitionMetrics, RejectsBadMatrices) {
  EXPECT_THROW(BestMatchesFrameAligned(DifferenceMatrix(0, 0), 2), std::invalid_argument);
  DifferenceMatrix with_nan = DifferenceMatrix::Zero(2, 2);
  with_nan(1, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(BestMatchesFrameAligned(with_nan, 2), std::invalid_argument);
  EXPECT_THROW(BestMatchesFrameAligned(DifferenceMatrix::Zero(3, 2), 2), std::invalid_argument);
  EXPECT_THROW(BestMatchesFrameAligned(DifferenceMatrix::Zero(2, 2), -1), std::invalid_argument);
  const std::vector<int> out_of_range = {0, 5};
  EXPECT_THROW(BestMatches(DifferenceMatrix::Zero(2, 2), out_of_range, 0), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::eval
