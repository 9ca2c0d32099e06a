#pragma once
// Area-weighted shrinking of an 8-bit grey image to a small float image with intensities in
// [0, 1]: each output cell is the mean of the source area it covers, pixels straddling a cell
// boundary shared by area (what cv::INTER_AREA computes; OpenRatSLAM resizes its templates this
// way). OpenCV's INTER_AREA takes a slow generic path for non-integer ratios (St Lucia: 560 ->
// 60 columns); this separable version costs a few microseconds.
//
// The weights depend only on the sizes, so they are computed once per AreaShrink.

#include <opencv2/core.hpp>

#include <vector>

namespace rslam::templates {

class AreaShrink {
 public:
  // Throws std::invalid_argument unless source_cols >= width >= 1 and source_rows >= height >= 1.
  AreaShrink(int source_cols, int source_rows, int width, int height);

  int source_cols() const { return source_cols_; }
  int source_rows() const { return source_rows_; }

  // source: CV_8UC1 of source_cols x source_rows (may be a view into a larger image); out
  // becomes height x width CV_32F. Throws std::invalid_argument on another size or type.
  void Apply(const cv::Mat& source, cv::Mat& out) const;

 private:
  // Along one axis: each source pixel's first cell and the share of the pixel inside it (the
  // rest falls in the next cell), and each cell's source pixels [begin, end): the last one may
  // straddle into the next cell, the one before `begin` may straddle into this one.
  struct Axis {
    std::vector<int> cell;
    std::vector<float> first_weight;
    std::vector<int> begin;
    std::vector<int> end;
  };
  static Axis MakeAxis(int source, int target);

  const int source_cols_;
  const int source_rows_;
  const int width_;
  const int height_;
  const Axis columns_;
  const Axis rows_;
};

}  // namespace rslam::templates
