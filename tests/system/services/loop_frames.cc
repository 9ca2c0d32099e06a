#include "tests/system/services/loop_frames.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <stdexcept>

namespace rslam::system_test {

namespace {

constexpr int kBand = 40;
constexpr int kScrollPx = 5;

// Smooth random texture: uniform values on a coarse grid, bilinearly enlarged.
cv::Mat Coarse(int width, int height, int cell, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat coarse(height / cell + 1, width / cell + 1, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 20, 235);
  cv::Mat fine;
  cv::resize(coarse, fine, cv::Size((width / cell + 1) * cell, (height / cell + 1) * cell), 0, 0, cv::INTER_LINEAR);
  return fine(cv::Rect(0, 0, width, height)).clone();
}

}  // namespace

cv::Mat LoopFrame(int places_per_lap, int index) {
  if (places_per_lap < 2 || index < 0) throw std::invalid_argument("LoopFrame: bad places_per_lap or index");
  const int place = index % places_per_lap;
  cv::Mat frame(kLoopFrameHeight, kLoopFrameWidth, CV_8UC1);
  // Rotation band: the camera turns counter-clockwise, so the scene moves towards larger x.
  const cv::Mat panorama = Coarse(places_per_lap * kScrollPx, kBand, 2, 1234);
  const int width = panorama.cols;
  const int offset = ((-place * kScrollPx) % width + width) % width;
  for (int x = 0; x < kLoopFrameWidth; ++x)
    panorama.col((offset + x) % width).copyTo(frame(cv::Rect(x, 0, 1, kBand)));
  Coarse(kLoopFrameWidth, kBand, 4, 5000 + place).copyTo(frame(cv::Rect(0, kBand, kLoopFrameWidth, kBand)));
  cv::RNG noise_rng(9000 + place);
  cv::Mat noise(kBand, kLoopFrameWidth, CV_8UC1);
  noise_rng.fill(noise, cv::RNG::UNIFORM, 70, 190);
  noise.copyTo(frame(cv::Rect(0, 2 * kBand, kLoopFrameWidth, kBand)));
  return frame;
}

void WriteLoopFrames(const std::filesystem::path& folder, int places_per_lap, int frames) {
  std::filesystem::create_directories(folder);
  for (int i = 0; i < frames; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", i);
    if (!cv::imwrite((folder / name).string(), LoopFrame(places_per_lap, i)))
      throw std::runtime_error("cannot write " + (folder / name).string());
  }
}

}  // namespace rslam::system_test
