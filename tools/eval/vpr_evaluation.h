#pragma once
// Scores a place-recognition method on frame-aligned sets (query i shows the place of
// reference i): single-frame or sequence matching (sequence_matcher.h) over a difference
// matrix, then recall@1 and recall@100%precision (place_recognition_metrics.h).

#include "tools/eval/difference_matrix.h"
#include "tools/eval/sequence_matcher.h"

namespace rslam::eval {

struct VprEvaluationOptions {
  int tolerance = 2;                  // frames either side of the true reference that count as correct
  int rival_exclusion = -1;           // frames around the best that are not rivals; < 0 = tolerance
  SequenceMatchingOptions sequence{.length = 1, .contrast_window = 0};
};

struct VprResult {
  double recall_at_1 = 0.0;
  double recall_at_100_precision = 0.0;                // confidence = margin over the best rival
  double recall_at_100_precision_by_difference = 0.0;  // confidence = best difference
  int queries = 0;
  int references = 0;
};

// Throws std::invalid_argument on bad matrices or options (see the functions it uses).
VprResult EvaluateFrameAligned(const DifferenceMatrix& differences, const VprEvaluationOptions& options);

}  // namespace rslam::eval
