#include "tools/eval/patch_normalised_sad.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rslam::eval {

cv::Mat PatchNormalise(const cv::Mat& grey, int patch_size) {
  if (grey.empty()) throw std::invalid_argument("PatchNormalise: empty image");
  if (grey.channels() != 1) {
    throw std::invalid_argument("PatchNormalise: expected a grey image, got " + std::to_string(grey.channels()) + " channels");
  }
  if (patch_size < 2) throw std::invalid_argument("PatchNormalise: patch_size must be >= 2");
  cv::Mat normalised;
  grey.convertTo(normalised, CV_32F);
  if (!cv::checkRange(normalised)) throw std::invalid_argument("PatchNormalise: image has NaN or inf pixels");
  // A flat block (sky, snow) has no contrast to normalise; keep it at zero instead of amplifying noise.
  constexpr double kMinimumSpread = 1e-6;
  for (int y = 0; y < normalised.rows; y += patch_size) {
    for (int x = 0; x < normalised.cols; x += patch_size) {
      const cv::Rect block(x, y, std::min(patch_size, normalised.cols - x), std::min(patch_size, normalised.rows - y));
      cv::Mat view = normalised(block);
      cv::Scalar mean, spread;
      cv::meanStdDev(view, mean, spread);
      if (spread[0] < kMinimumSpread) {
        view.setTo(0.0f);
      } else {
        view.convertTo(view, CV_32F, 1.0 / spread[0], -mean[0] / spread[0]);
      }
    }
  }
  return normalised;
}

namespace {

// One row per image, the normalised pixels flattened, so a pair's SAD is one vectorised pass.
Eigen::MatrixXf NormalisedRows(std::span<const cv::Mat> images, int patch_size, const cv::Size& size,
                               const char* which) {
  Eigen::MatrixXf rows(static_cast<Eigen::Index>(images.size()), static_cast<Eigen::Index>(size.area()));
  for (std::size_t k = 0; k < images.size(); ++k) {
    if (images[k].size() != size) {
      throw std::invalid_argument(std::string(which) + " image " + std::to_string(k) + " is " +
                                  std::to_string(images[k].cols) + "x" + std::to_string(images[k].rows) +
                                  ", expected " + std::to_string(size.width) + "x" + std::to_string(size.height));
    }
    const cv::Mat normalised = PatchNormalise(images[k], patch_size);
    for (int y = 0; y < size.height; ++y) {
      const float* src = normalised.ptr<float>(y);
      for (int x = 0; x < size.width; ++x) rows(static_cast<Eigen::Index>(k), y * size.width + x) = src[x];
    }
  }
  return rows;
}

}  // namespace

DifferenceMatrix PatchSadDifferences(std::span<const cv::Mat> references, std::span<const cv::Mat> queries,
                                     int patch_size) {
  if (references.empty() || queries.empty()) throw std::invalid_argument("PatchSadDifferences: no references or no queries");
  const cv::Size size = references.front().size();
  if (size.area() == 0) throw std::invalid_argument("PatchSadDifferences: reference image 0 is empty");
  const Eigen::MatrixXf reference_rows = NormalisedRows(references, patch_size, size, "reference");
  const Eigen::MatrixXf query_rows = NormalisedRows(queries, patch_size, size, "query");
  DifferenceMatrix differences(query_rows.rows(), reference_rows.rows());
  const double pixels = static_cast<double>(size.area());
  for (Eigen::Index i = 0; i < query_rows.rows(); ++i) {
    for (Eigen::Index j = 0; j < reference_rows.rows(); ++j) {
      differences(i, j) = static_cast<double>((query_rows.row(i) - reference_rows.row(j)).cwiseAbs().sum()) / pixels;
    }
  }
  return differences;
}

DifferenceMatrix BaselinePatchSad(std::span<const cv::Mat> references, std::span<const cv::Mat> queries) {
  constexpr int kBaselinePatchSize = 8;
  return PatchSadDifferences(references, queries, kBaselinePatchSize);
}

}  // namespace rslam::eval
