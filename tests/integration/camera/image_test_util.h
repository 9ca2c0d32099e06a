#pragma once
// Helpers shared by the camera, odometry and templates integration tests: deterministic test
// images, image messages, and the heartbeat of a service.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "common/bus/subscriber.h"
#include "services/camera/image_message.h"

namespace rslam::testing {

// Uniform noise, the same for the same seed (a texture every shift and crop can be told by).
inline cv::Mat RandomTexture(int width, int height, int channels, uint64_t seed) {
  cv::Mat image(height, width, channels == 3 ? CV_8UC3 : CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

// A smooth random texture: noise blurred by area-resizing up (keeps profile comparisons
// well-behaved for odometry).
inline cv::Mat SmoothTexture(int width, int height, uint64_t seed) {
  const cv::Mat coarse = RandomTexture((width + 3) / 4, (height + 3) / 4, 1, seed);
  cv::Mat fine;
  cv::resize(coarse, fine, cv::Size(width, height), 0, 0, cv::INTER_LINEAR);
  return fine;
}

inline msg::Image ImageMessage(const cv::Mat& image, uint64_t seq, int64_t stamp_ns,
                               const std::string& robot = "robot1") {
  msg::Image m;
  m.header = {robot, seq, stamp_ns};
  camera::FillImageMessage(image, m);
  return m;
}

// The latest heartbeat of `service` that satisfies pred, waiting up to timeout.
inline std::optional<msg::ServiceStatus> AwaitHeartbeat(bus::Subscriber<msg::ServiceStatus>& heartbeats,
                                                        const std::string& service,
                                                        const std::function<bool(const msg::ServiceStatus&)>& pred,
                                                        std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (auto s = heartbeats.TakeOne(std::chrono::milliseconds(200)); s && s->service == service && pred(*s)) return s;
  }
  return std::nullopt;
}

}  // namespace rslam::testing
