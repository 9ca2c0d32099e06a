#pragma once
// Grey conversion of only the rows of a camera frame that the RatSLAM stages read.
//
// The odometry and template stages read fixed crops of the grey frame (St Lucia: rows 75-430 of
// 480), and grey conversion is per pixel, so converting whole rows [row_begin, row_end) gives
// those crops bit for bit as converting the whole frame would. Whole rows rather than the crops
// themselves: frames that come from main memory (a long recording) stream at the memory's speed
// only when read front to back; converting the narrow crops alone was slower than converting the
// whole frame (measured on a 118 MB frame pool, see tests/bench/core).
//
// BGR frames are converted by an AVX2 kernel with OpenCV's own fixed-point weights when the CPU
// has AVX2 and the kernel gives exactly cv::cvtColor(COLOR_BGR2GRAY)'s result for every one of
// the 2^24 colours (checked once per process on first use, a few tens of ms; another OpenCV
// version with other weights falls back to cv::cvtColor). BGRA frames use cv::cvtColor on the
// rows.

#include <opencv2/core.hpp>

namespace rslam::run {

// Rows [row_begin, row_end) of image (CV_8UC1, CV_8UC3 BGR or CV_8UC4 BGRA) converted to grey in
// buffer, which becomes (or stays: no allocation per frame) a CV_8UC1 image of the frame's
// size; its other rows keep whatever they held. A grey image is returned as is (buffer left
// alone). Throws std::invalid_argument for an empty image, a depth other than 8 bits, 2
// channels, or a row range not within the image (row_begin < row_end required).
cv::Mat ToGreyRows(const cv::Mat& image, int row_begin, int row_end, cv::Mat& buffer);

// True when the AVX2 kernel is in use: the CPU has AVX2 and the kernel matches
// cv::cvtColor(COLOR_BGR2GRAY) on all 2^24 colours. For tests and benchmark reports.
bool FastBgrToGreyInUse();

}  // namespace rslam::run
