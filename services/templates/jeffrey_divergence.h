#pragma once
// Jeffrey divergence between two histograms (Prasser et al. 2004, paper 001 eq. 1):
//   d_J(H, K) = sum_i h_i log(2 h_i / (h_i + k_i)) + k_i log(2 k_i / (h_i + k_i))
// with 0 log(0) = 0 and the natural log. For histograms normalised to sum 1 it lies in
// [0, 2 ln 2]; it scales linearly with the histograms' total (the paper's 300 is in pixel counts).
//
// The library compares one view against thousands of histograms, so it splits the sum:
//   d_J = S(H) + S(K) - sum_i (h_i + k_i) log(h_i + k_i),   S(H) = sum_i h_i log(2 h_i),
// precomputing S per stored histogram: one log per bin instead of two.

#include <span>

namespace rslam::templates {

// Direct eq. 1. Histograms of equal length, entries finite and >= 0 (std::invalid_argument otherwise).
double JeffreyDivergence(std::span<const float> h, std::span<const float> k);

// S(H) above.
double JeffreySelfTerm(std::span<const float> h);

// d_J from precomputed self terms (no checks: the hot path).
double JeffreyDivergenceFromSelfTerms(std::span<const float> h, double self_h, std::span<const float> k, double self_k);

// A cheap lower bound of d_J(H, K) (no logarithms), for skipping histograms that cannot be the
// closest. Per bin, with s = h + k and t = (h - k) / s, eq. 1's term is
//   s/2 [(1 + t) log(1 + t) + (1 - t) log(1 - t)] = s/2 (t^2 + t^4/6 + t^6/15 + ...) >= s t^2 / 2,
// so d_J >= sum_i (h_i - k_i)^2 / (2 (h_i + k_i)) (half the triangular discrimination; tight
// for similar histograms, which are the ones that matter). Returned 0.1% and 1e-5 below that,
// which covers float rounding in both this and the divergence as computed, so a histogram whose
// bound exceeds a value also has a computed divergence above it. Any non-negative histograms.
double JeffreyDivergenceLowerBound(std::span<const float> h, std::span<const float> k);

}  // namespace rslam::templates
