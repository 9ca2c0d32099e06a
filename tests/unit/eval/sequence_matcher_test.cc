#include "tools/eval/sequence_matcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>

#include "tools/eval/vpr_evaluation.h"

namespace rslam::eval {
namespace {

TEST(SequenceMatcher, LengthOneIsTheDifferenceMatrix) {
  const DifferenceMatrix d = DifferenceMatrix::Random(5, 7).cwiseAbs();
  EXPECT_TRUE(SequenceMatchDifferences(d, {.length = 1, .contrast_window = 0}).isApprox(d));
}

TEST(SequenceMatcher, AveragesTheDiagonalEndingAtEachEntryUsingWhatExists) {
  DifferenceMatrix d(3, 3);
  d << 1, 2, 3,
       4, 5, 6,
       7, 8, 9;
  const DifferenceMatrix s = SequenceMatchDifferences(d, {.length = 2, .contrast_window = 0});
  EXPECT_DOUBLE_EQ(s(0, 0), 1.0);              // first query: only itself
  EXPECT_DOUBLE_EQ(s(0, 2), 3.0);
  EXPECT_DOUBLE_EQ(s(1, 1), (5.0 + 1.0) / 2);
  EXPECT_DOUBLE_EQ(s(2, 2), (9.0 + 5.0) / 2);  // length 2: 1 is out of the window
  EXPECT_DOUBLE_EQ(s(1, 2), (6.0 + 2.0) / 2);
  // Reference 0 cannot end a 2-frame diagonal: no candidate, the row's worst valid score.
  EXPECT_DOUBLE_EQ(s(2, 0), std::max(s(2, 1), s(2, 2)));
  EXPECT_DOUBLE_EQ(s(1, 0), std::max(s(1, 1), s(1, 2)));
}

TEST(SequenceMatcher, RecoversTheDiagonalUnderNoiseWhereSingleFramesFail) {
  // The true place has a slightly lower difference than any other, buried in noise much larger
  // than that advantage: single frames mostly pick noise, a run of 20 frames averages it out.
  constexpr int kFrames = 200;
  std::mt19937 random(42);
  std::normal_distribution<double> noise(0.0, 0.2);
  DifferenceMatrix d(kFrames, kFrames);
  for (int i = 0; i < kFrames; ++i) {
    for (int j = 0; j < kFrames; ++j) d(i, j) = 1.0 + noise(random) - (i == j ? 0.25 : 0.0);
  }
  VprEvaluationOptions single;
  single.tolerance = 0;
  VprEvaluationOptions sequence = single;
  sequence.sequence.length = 20;
  const VprResult single_result = EvaluateFrameAligned(d, single);
  const VprResult sequence_result = EvaluateFrameAligned(d, sequence);
  EXPECT_LT(single_result.recall_at_1, 0.3);
  EXPECT_GT(sequence_result.recall_at_1, 0.85);
  EXPECT_GT(sequence_result.recall_at_100_precision, single_result.recall_at_100_precision);
}

TEST(SequenceMatcher, ContrastEnhancementRemovesAReferenceThatLooksLikeEverything) {
  // Reference 3 is a "hub" (a featureless frame): lower difference to every query than the
  // true place. Raw sequence matching is drawn to it; row-wise contrast enhancement is not.
  constexpr int kFrames = 30;
  DifferenceMatrix d = DifferenceMatrix::Constant(kFrames, kFrames, 1.0);
  for (int i = 0; i < kFrames; ++i) {
    d(i, i) = 0.8;
    for (int hub = 3; hub < 3 + 10; ++hub) d(i, hub) = 0.5;
  }
  VprEvaluationOptions raw;
  raw.tolerance = 0;
  raw.sequence.length = 5;
  VprEvaluationOptions enhanced = raw;
  enhanced.sequence.contrast_window = 5;
  EXPECT_LT(EvaluateFrameAligned(d, raw).recall_at_1, 0.7);
  EXPECT_GT(EvaluateFrameAligned(d, enhanced).recall_at_1, EvaluateFrameAligned(d, raw).recall_at_1);
}

TEST(SequenceMatcher, RejectsBadOptions) {
  const DifferenceMatrix d = DifferenceMatrix::Ones(3, 3);
  EXPECT_THROW(SequenceMatchDifferences(d, {.length = 0, .contrast_window = 0}), std::invalid_argument);
  EXPECT_THROW(SequenceMatchDifferences(d, {.length = 2, .contrast_window = 2}), std::invalid_argument);
  EXPECT_THROW(SequenceMatchDifferences(DifferenceMatrix(0, 3), {.length = 2, .contrast_window = 0}),
               std::invalid_argument);
}

}  // namespace
}  // namespace rslam::eval
