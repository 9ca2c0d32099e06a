#pragma once
// Patch-normalised sum of absolute differences, the classic appearance-invariant image
// comparison of SeqSLAM (Milford & Wyeth 2012): each non-overlapping patch x patch block of a
// grey image is shifted and scaled to zero mean and unit standard deviation (so lighting and
// contrast changes between seasons cancel), then two images differ by the mean absolute
// difference of their normalised pixels.
//
// BaselinePatchSad is the reference baseline of the evaluation (8x8 blocks, full image, single
// frame): any place-recognition method in this project is compared against it.

#include <opencv2/core.hpp>

#include <span>

#include "tools/eval/difference_matrix.h"

namespace rslam::eval {

// Grey 8-bit or float image -> CV_32F image, each block normalised. Trailing rows/columns that
// do not fill a block are normalised as a smaller block. Throws std::invalid_argument for an
// empty or multi-channel image or patch_size < 2.
cv::Mat PatchNormalise(const cv::Mat& grey, int patch_size);

// D(i, j) = mean |PatchNormalise(query i) - PatchNormalise(reference j)|. All images must have
// one size (std::invalid_argument naming the first that differs).
DifferenceMatrix PatchSadDifferences(std::span<const cv::Mat> references, std::span<const cv::Mat> queries,
                                     int patch_size);

// The baseline: PatchSadDifferences with 8x8 blocks.
DifferenceMatrix BaselinePatchSad(std::span<const cv::Mat> references, std::span<const cv::Mat> queries);

}  // namespace rslam::eval
