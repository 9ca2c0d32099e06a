#pragma once
// msg::Image <-> cv::Mat, and the arrival checks every image reader applies (sizes agree with
// width, height, step and encoding; only mono8 and bgr8), shared by the camera, odometry and
// templates services.

#include <opencv2/core.hpp>

#include <cstdint>
#include <string>

#include "rslam/msg/all_messages.h"

namespace rslam::camera {

inline constexpr const char* kMono8 = "mono8";
inline constexpr const char* kBgr8 = "bgr8";

// Why the message is not a usable image ("" when it is): unknown encoding, zero or more than
// max_pixels pixels, step shorter than a row, data size different from step * height.
std::string ImageMessageProblem(const msg::Image& image, uint64_t max_pixels);

// A cv::Mat header over the message's bytes (no copy; valid while the message lives).
// Precondition: ImageMessageProblem(image) is empty.
cv::Mat ImageView(const msg::Image& image);

// The image as 8-bit grey (a view of mono8 data, or a converted copy of bgr8).
cv::Mat GreyImage(const msg::Image& image);

// Fills width, height, encoding, step and data from a CV_8UC1 (mono8) or CV_8UC3 (bgr8) image;
// the header is left as it is. Throws std::invalid_argument for other types.
void FillImageMessage(const cv::Mat& image, msg::Image& out);

}  // namespace rslam::camera
