#pragma once
// Deterministic synthetic images for the template tests.
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace rslam::templates::testing {

// A smooth random texture: coarse uniform noise blown up by cubic interpolation.
inline cv::Mat Texture(int width, int height, uint64_t seed, int cell = 8) {
  cv::RNG rng(seed);
  cv::Mat coarse(height / cell + 2, width / cell + 2, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 20, 235);
  cv::Mat fine;
  cv::resize(coarse, fine, cv::Size(width + 2 * cell, height + 2 * cell), 0, 0, cv::INTER_CUBIC);
  return fine(cv::Rect(cell, cell, width, height)).clone();
}

// The image with its columns rotated right by `shift` (wrapping): column x shows old x - shift.
inline cv::Mat RollColumns(const cv::Mat& image, int shift) {
  const int w = image.cols;
  shift = ((shift % w) + w) % w;
  cv::Mat out(image.size(), image.type());
  if (shift == 0) return image.clone();
  image(cv::Rect(w - shift, 0, shift, image.rows)).copyTo(out(cv::Rect(0, 0, shift, image.rows)));
  image(cv::Rect(0, 0, w - shift, image.rows)).copyTo(out(cv::Rect(shift, 0, w - shift, image.rows)));
  return out;
}

inline cv::Mat AddNoise(const cv::Mat& grey, double sigma, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat noise(grey.size(), CV_16SC1);
  rng.fill(noise, cv::RNG::NORMAL, 0, sigma);
  cv::Mat wide, out;
  grey.convertTo(wide, CV_16SC1);
  wide += noise;
  wide.convertTo(out, CV_8UC1);
  return out;
}

}  // namespace rslam::templates::testing
