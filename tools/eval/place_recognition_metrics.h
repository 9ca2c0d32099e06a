#pragma once
// Visual place recognition scores from a difference matrix (see difference_matrix.h).
//
// recall@1: the share of queries whose best reference (lowest difference) lies within
// `tolerance` frames of the query's true reference.
// recall@100%precision: the largest share of queries that can be accepted by one confidence
// threshold while every accepted match is correct. The confidence of a match is its margin over
// the best rival: (second best - best) / standard deviation of the query's row, the second best
// taken outside a window of `rival_exclusion` frames around the best (the neighbours of the best
// frame look alike and are not rivals). This is the distinctiveness ratio test of SeqSLAM made
// independent of the sign and scale of the differences, which contrast enhancement
// (sequence_matcher.h) makes negative. A larger margin is a more confident match; queries with
// equal margins are accepted or refused together.

#include <cstddef>
#include <span>
#include <vector>

#include "tools/eval/difference_matrix.h"

namespace rslam::eval {

struct PlaceMatch {
  int query = 0;
  int reference = 0;               // argmin of the query's row
  int true_reference = 0;
  double best_difference = 0.0;
  double second_best_difference = 0.0;  // outside the rival exclusion window; +inf when none
  double margin = 0.0;                  // (second best - best) / row spread; +inf when no rival
  bool correct = false;
};

// One match per row. true_reference[i] is the index of the reference showing query i's place.
// Throws std::invalid_argument on an empty matrix, non-finite entries, a true_reference of the
// wrong size or out of range, or a negative tolerance or rival_exclusion.
// rival_exclusion < 0 means "the same as tolerance".
std::vector<PlaceMatch> BestMatches(const DifferenceMatrix& differences,
                                    std::span<const int> true_reference, int tolerance,
                                    int rival_exclusion = -1);

// The same with true_reference[i] = i (frame-aligned sets).
std::vector<PlaceMatch> BestMatchesFrameAligned(const DifferenceMatrix& differences, int tolerance,
                                                int rival_exclusion = -1);

double RecallAtOne(std::span<const PlaceMatch> matches);

// Confidence = margin over the best rival (see above).
double RecallAtFullPrecision(std::span<const PlaceMatch> matches);

// Confidence = the best difference itself (lower = more confident); for comparison.
double RecallAtFullPrecisionByDifference(std::span<const PlaceMatch> matches);

}  // namespace rslam::eval
