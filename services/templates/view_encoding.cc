#include "services/templates/view_encoding.h"

#include "common/image/crop.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

namespace rslam::templates {

namespace {

std::string Describe(const TemplateConfig& c) {
  std::ostringstream os;
  os << c.mode << " crop x[" << c.image_crop_x_min << "," << c.image_crop_x_max << ") y[" << c.image_crop_y_min
     << "," << c.image_crop_y_max << ")";
  if (c.mode == "histogram") {
    os << " bins " << c.histogram_bins << " stretch " << c.histogram_normalise_intensity << " rotation "
       << c.rotation_image_width << "x" << c.rotation_image_height << " dead";
    for (int d : c.dead_zone_columns) os << " " << d;
  } else {
    os << " size " << c.template_x_size << "x" << (c.mode == "column" ? 1 : c.template_y_size) << " norm "
       << c.normalisation << " patch " << c.patch_normalisation << " minstd " << c.min_patch_normalisation_std;
  }
  return os.str();
}

// Clamps to [0, 1], scales to 0..255 and rounds half away from zero (as std::lround), without
// the library call or branches (after normalisation many values clip, and the rounding
// direction is a coin toss: both would mispredict).
uint8_t Quantise(float v) {
  const float scaled = std::min(std::max(v, 0.0f), 1.0f) * 255.0f;
  const int whole = static_cast<int>(scaled);
  return static_cast<uint8_t>(whole + static_cast<int>(scaled - static_cast<float>(whole) >= 0.5f));
}

}  // namespace

ViewEncoder::ViewEncoder(const TemplateConfig& config)
    : config_(config),
      histogram_mode_(config.mode == "histogram"),
      width_(histogram_mode_ ? config.rotation_image_width : config.template_x_size),
      height_(histogram_mode_ ? config.rotation_image_height : (config.mode == "column" ? 1 : config.template_y_size)),
      histogram_bins_(histogram_mode_ ? config.histogram_bins : 0),
      description_(Describe(config)),
      fixed_shrink_(FixedShrink(config, width_, height_)) {}

std::optional<AreaShrink> ViewEncoder::FixedShrink(const TemplateConfig& config, int width, int height) {
  // Only a crop with explicit edges has a size that does not depend on the image.
  if (config.image_crop_x_max == -1 || config.image_crop_y_max == -1) return std::nullopt;
  const int crop_cols = config.image_crop_x_max - config.image_crop_x_min;
  const int crop_rows = config.image_crop_y_max - config.image_crop_y_min;
  if (crop_cols < width || crop_rows < height) return std::nullopt;  // Encode refuses every image
  return AreaShrink(crop_cols, crop_rows, width, height);
}

void ViewEncoder::Shrink(const cv::Mat& crop, cv::Mat& out) const {
  if (fixed_shrink_) {
    fixed_shrink_->Apply(crop, out);
  } else {
    AreaShrink(crop.cols, crop.rows, width_, height_).Apply(crop, out);
  }
}

cv::Rect ViewEncoder::ResolveCrop(const cv::Mat& image) const {
  if (image.empty()) throw std::invalid_argument("TemplateLibrary: empty image");
  if (image.type() != CV_8UC1 && image.type() != CV_8UC3 && image.type() != CV_8UC4) {
    throw std::invalid_argument("TemplateLibrary: image must be CV_8UC1 (grey), CV_8UC3 (BGR) or CV_8UC4 (BGRA), got type " +
                                std::to_string(image.type()));
  }
  return rslam::ResolveCrop(config_.image_crop_x_min, config_.image_crop_x_max, config_.image_crop_y_min,
                           config_.image_crop_y_max, image.size(), "TemplateLibrary:");
}

void ViewEncoder::Encode(const cv::Mat& image, EncodedView& out) const {
  cv::Mat crop = image(ResolveCrop(image));
  if (crop.channels() != 1) {
    // Grey conversion is per pixel: converting only the crop gives the crop of the converted
    // frame, bit for bit.
    cv::Mat grey_crop;
    cv::cvtColor(crop, grey_crop, crop.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
    crop = grey_crop;
  }
  if (crop.cols < width_ || crop.rows < height_) {
    throw std::invalid_argument("TemplateLibrary: the " + std::to_string(crop.cols) + "x" + std::to_string(crop.rows) +
                                " crop is smaller than the " + std::to_string(width_) + "x" + std::to_string(height_) +
                                " template");
  }
  if (histogram_mode_) {
    EncodeHistogram(crop, out);
  } else {
    EncodeGrid(crop, out);
  }
  uint32_t total = 0;
  for (uint8_t p : out.pixels) total += p;
  out.mean = static_cast<float>(total) / (255.0f * static_cast<float>(out.pixels.size()));
}

void ViewEncoder::EncodeGrid(const cv::Mat& crop, EncodedView& out) const {
  cv::Mat view;
  Shrink(crop, view);
  // OpenRatSLAM's vt_normalisation: a global gain so the mean is `normalisation`.
  if (config_.normalisation > 0) {
    const double mean = cv::mean(view)[0];
    if (mean > 1e-6) {
      view *= config_.normalisation / mean;
      for (int y = 0; y < view.rows; ++y) {  // cv::min(view, 1.0): the same floats, without its overhead
        float* row = view.ptr<float>(y);
        for (int x = 0; x < view.cols; ++x) row[x] = std::min(row[x], 1.0f);
      }
    }
  }
  // OpenRatSLAM's vt_patch_normalise: z-score over a (2r+1)^2 patch, edges clamped, mapped
  // from [-3, 3] sigma to [0, 1].
  if (config_.patch_normalisation > 0) {
    // Box sums from integral images of the edge-replicated view (replication = clamped
    // indices, as OpenRatSLAM clamps): O(1) per pixel whatever the radius.
    const int r = config_.patch_normalisation;
    const int side = 2 * r + 1;
    const double count = static_cast<double>(side) * side;
    cv::Mat padded, sum, sum_sq;
    cv::copyMakeBorder(view, padded, r, r, r, r, cv::BORDER_REPLICATE);
    cv::integral(padded, sum, sum_sq, CV_64F, CV_64F);
    cv::Mat normalised(view.size(), CV_32F);
    for (int y = 0; y < height_; ++y) {
      const double* s0 = sum.ptr<double>(y);
      const double* s1 = sum.ptr<double>(y + side);
      const double* q0 = sum_sq.ptr<double>(y);
      const double* q1 = sum_sq.ptr<double>(y + side);
      const float* in = view.ptr<float>(y);
      float* out_row = normalised.ptr<float>(y);
      for (int x = 0; x < width_; ++x) {
        const double box = s1[x + side] - s1[x] - s0[x + side] + s0[x];
        const double box_sq = q1[x + side] - q1[x] - q0[x + side] + q0[x];
        const double mean = box / count;
        const double stddev = std::sqrt(std::max(0.0, box_sq / count - mean * mean));
        if (stddev <= 1e-6 || stddev < config_.min_patch_normalisation_std) {
          out_row[x] = 0.5f;
        } else {
          out_row[x] = static_cast<float>(((in[x] - mean) / stddev + 3.0) / 6.0);
        }
      }
    }
    view = normalised;
  }
  out.pixels.resize(static_cast<std::size_t>(width_) * height_);
  for (int y = 0; y < height_; ++y) {
    const float* row = view.ptr<float>(y);
    for (int x = 0; x < width_; ++x) out.pixels[static_cast<std::size_t>(y) * width_ + x] = Quantise(row[x]);
  }
  out.histogram.clear();
}

void ViewEncoder::EncodeHistogram(const cv::Mat& crop, EncodedView& out) const {
  cv::Mat panorama = crop;
  // Which crop columns are dead: a crop column belongs to rotation column c * W / crop_width.
  // The live ones as runs [begin, end), so the pixel loops below have no per-pixel test.
  std::vector<uint8_t> dead_rotation_column(width_, 0);
  for (int c : config_.dead_zone_columns) dead_rotation_column[c] = 1;
  std::vector<std::pair<int, int>> live_runs;
  for (int x = 0; x < crop.cols; ++x) {
    if (dead_rotation_column[static_cast<int64_t>(x) * width_ / crop.cols]) continue;
    if (!live_runs.empty() && live_runs.back().second == x) {
      ++live_runs.back().second;
    } else {
      live_runs.emplace_back(x, x + 1);
    }
  }

  if (config_.histogram_normalise_intensity) {
    uint8_t lo = 255, hi = 0;
    for (int y = 0; y < crop.rows; ++y) {
      const uint8_t* row = crop.ptr<uint8_t>(y);
      for (auto [begin, end] : live_runs) {
        for (int x = begin; x < end; ++x) {
          lo = std::min(lo, row[x]);
          hi = std::max(hi, row[x]);
        }
      }
    }
    if (hi > lo) {
      cv::Mat stretched;
      crop.convertTo(stretched, CV_8U, 255.0 / (hi - lo), -255.0 * lo / (hi - lo));
      panorama = stretched;
    }
  }

  // Four interleaved partial histograms: consecutive pixels often fall in the same bin, and one
  // array would chain every increment through a store and a load.
  uint8_t bin_of[256];
  for (int v = 0; v < 256; ++v) bin_of[v] = static_cast<uint8_t>(v * histogram_bins_ / 256);
  std::vector<uint32_t> partial(static_cast<std::size_t>(4) * histogram_bins_, 0);
  uint32_t total = 0;
  for (int y = 0; y < panorama.rows; ++y) {
    const uint8_t* row = panorama.ptr<uint8_t>(y);
    for (auto [begin, end] : live_runs) {
      int x = begin;
      for (; x + 4 <= end; x += 4) {
        ++partial[bin_of[row[x]]];
        ++partial[histogram_bins_ + bin_of[row[x + 1]]];
        ++partial[2 * histogram_bins_ + bin_of[row[x + 2]]];
        ++partial[3 * histogram_bins_ + bin_of[row[x + 3]]];
      }
      for (; x < end; ++x) ++partial[bin_of[row[x]]];
      total += static_cast<uint32_t>(end - begin);
    }
  }
  out.histogram.assign(histogram_bins_, 0.0f);
  for (int b = 0; b < histogram_bins_; ++b) {
    const uint32_t count = partial[b] + partial[histogram_bins_ + b] + partial[2 * histogram_bins_ + b] +
                           partial[3 * histogram_bins_ + b];
    out.histogram[b] = total ? static_cast<float>(count) / static_cast<float>(total) : 0.0f;
  }

  cv::Mat small;
  Shrink(panorama, small);
  out.pixels.resize(static_cast<std::size_t>(width_) * height_);
  for (int y = 0; y < height_; ++y) {
    const float* row = small.ptr<float>(y);
    for (int x = 0; x < width_; ++x) out.pixels[static_cast<std::size_t>(y) * width_ + x] = Quantise(row[x]);
  }
}

}  // namespace rslam::templates
