#pragma once
// How a grey camera image becomes a template (the "view"), for the three TemplateLibrary modes:
//   column:    crop -> area-resize to template_x_size x 1 (column-intensity array, paper 000)
//   patch:     crop -> area-resize to template_x_size x template_y_size -> optional mean
//              normalisation -> optional local patch normalisation (OpenRatSLAM local_view_match)
//   histogram: crop (the panorama) -> optional intensity stretch -> histogram_bins-bin histogram
//              normalised to sum 1 (dead-zone columns excluded), and the panorama area-resized to
//              rotation_image_width x rotation_image_height for rotation recovery (paper 001)
// Pixels are stored as 8 bits (value * 255, rounded): exact to save, and 16 per SIMD lane
// when matching.

#include <opencv2/core.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "services/templates/area_shrink.h"
#include "services/templates/template_config.h"

namespace rslam::templates {

struct EncodedView {
  std::vector<uint8_t> pixels;   // width * height, row-major
  float mean = 0.0f;             // mean of pixels / 255
  std::vector<float> histogram;  // histogram mode only
};

class ViewEncoder {
 public:
  explicit ViewEncoder(const TemplateConfig& config);

  int width() const { return width_; }
  int height() const { return height_; }
  int histogram_bins() const { return histogram_bins_; }

  // image: CV_8UC1 grey, or CV_8UC3 BGR / CV_8UC4 BGRA, of which only the crop is converted
  // (exactly as cv::COLOR_BGR(A)2GRAY converts the whole frame). Throws std::invalid_argument
  // for an empty image, another type, or one smaller than the crop.
  void Encode(const cv::Mat& image, EncodedView& out) const;

  // The preprocessing settings as text; equal strings mean comparable templates.
  const std::string& description() const { return description_; }

 private:
  cv::Rect ResolveCrop(const cv::Mat& image) const;
  void EncodeGrid(const cv::Mat& crop, EncodedView& out) const;
  void EncodeHistogram(const cv::Mat& crop, EncodedView& out) const;
  static std::optional<AreaShrink> FixedShrink(const TemplateConfig& config, int width, int height);
  void Shrink(const cv::Mat& crop, cv::Mat& out) const;

  const TemplateConfig config_;
  const bool histogram_mode_;
  const int width_;
  const int height_;
  const int histogram_bins_;
  const std::string description_;
  const std::optional<AreaShrink> fixed_shrink_;  // when the crop's size is fixed by the config
};

}  // namespace rslam::templates
