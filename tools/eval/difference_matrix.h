#pragma once
// The one input of the place-recognition harness: D(i, j) = how different query frame i looks
// from reference frame j (lower = more alike), N_query x N_ref. Whoever builds it (the template
// library, the baseline) decides the units; the harness only compares values within it.

#include <Eigen/Core>

namespace rslam::eval {

using DifferenceMatrix = Eigen::MatrixXd;  // rows = queries, columns = references

}  // namespace rslam::eval
