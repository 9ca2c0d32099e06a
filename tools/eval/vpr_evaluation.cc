#include "tools/eval/vpr_evaluation.h"

#include "tools/eval/place_recognition_metrics.h"

namespace rslam::eval {

VprResult EvaluateFrameAligned(const DifferenceMatrix& differences, const VprEvaluationOptions& options) {
  const DifferenceMatrix scores = SequenceMatchDifferences(differences, options.sequence);
  const std::vector<PlaceMatch> matches = BestMatchesFrameAligned(scores, options.tolerance, options.rival_exclusion);
  VprResult result;
  result.recall_at_1 = RecallAtOne(matches);
  result.recall_at_100_precision = RecallAtFullPrecision(matches);
  result.recall_at_100_precision_by_difference = RecallAtFullPrecisionByDifference(matches);
  result.queries = static_cast<int>(differences.rows());
  result.references = static_cast<int>(differences.cols());
  return result;
}

}  // namespace rslam::eval
