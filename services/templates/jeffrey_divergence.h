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

}  // namespace rslam::templates
