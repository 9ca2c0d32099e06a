#pragma once
// Sequence matching in the manner of SeqSLAM (Milford & Wyeth 2012): a place is recognised by
// a run of frames rather than by one frame. The score of (query i, reference j) is the mean of
// the differences along the diagonal ending there,
//
//   S(i, j) = 1/K * sum_{k=0}^{K-1} D(i - k, j - k),   K = min(L, i + 1),
//
// i.e. a constant velocity of one reference frame per query frame (the sets evaluated here are
// frame-aligned), looking back only at queries already seen, so it works online. An early query
// (i < L - 1) uses the K = i + 1 frames that exist. A reference too early to end a diagonal of
// K frames (j < K - 1) is no candidate: it gets the row's largest valid score, because the mean
// of a shorter diagonal is noisier and its lucky lows would beat every full-length diagonal.
//
// Optional local contrast enhancement (SeqSLAM's D-hat): each entry is first normalised by the
// mean and standard deviation of its row over a window of references centred on it, which
// stops a query that differs from everything (glare, a tunnel) from dominating a diagonal.

#include "tools/eval/difference_matrix.h"

namespace rslam::eval {

struct SequenceMatchingOptions {
  int length = 10;           // L; 1 = single-frame matching (S = D)
  int contrast_window = 0;   // references in the normalisation window; 0 = off, else >= 3
};

// Throws std::invalid_argument for length < 1, a contrast window in 1..2, an empty matrix or
// non-finite entries.
DifferenceMatrix SequenceMatchDifferences(const DifferenceMatrix& differences,
                                          const SequenceMatchingOptions& options);

// D-hat alone (see above); window >= 3.
DifferenceMatrix LocalContrastEnhance(const DifferenceMatrix& differences, int window);

}  // namespace rslam::eval
