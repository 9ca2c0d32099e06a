#include "services/camera/image_message.h"

#include <opencv2/imgproc.hpp>

#include <stdexcept>

namespace rslam::camera {

std::string ImageMessageProblem(const msg::Image& image, uint64_t max_pixels) {
  uint64_t channels = 0;
  if (image.encoding == kBgr8) {
    channels = 3;
  } else if (image.encoding == kMono8) {
    channels = 1;
  } else {
    return "unknown encoding '" + image.encoding.substr(0, 32) + "' (mono8 or bgr8)";
  }
  const uint64_t pixels = uint64_t{image.width} * image.height;
  if (pixels == 0) return "empty image (" + std::to_string(image.width) + "x" + std::to_string(image.height) + ")";
  if (pixels > max_pixels)
    return std::to_string(image.width) + "x" + std::to_string(image.height) + " exceeds " +
           std::to_string(max_pixels) + " pixels";
  if (uint64_t{image.step} < uint64_t{image.width} * channels)
    return "step " + std::to_string(image.step) + " is shorter than a row of " +
           std::to_string(uint64_t{image.width} * channels) + " bytes";
  if (uint64_t{image.step} * image.height != image.data.size())
    return "data holds " + std::to_string(image.data.size()) + " bytes, step x height is " +
           std::to_string(uint64_t{image.step} * image.height);
  return {};
}

cv::Mat ImageView(const msg::Image& image) {
  const int type = image.encoding == kBgr8 ? CV_8UC3 : CV_8UC1;
  // OpenCV wants a non-const pointer; the view is only read.
  return cv::Mat(static_cast<int>(image.height), static_cast<int>(image.width), type,
                 const_cast<uint8_t*>(image.data.data()), image.step);
}

cv::Mat GreyImage(const msg::Image& image) {
  const cv::Mat view = ImageView(image);
  if (view.type() == CV_8UC1) return view;
  cv::Mat grey;
  cv::cvtColor(view, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

void FillImageMessage(const cv::Mat& image, msg::Image& out) {
  if (image.empty() || (image.type() != CV_8UC1 && image.type() != CV_8UC3))
    throw std::invalid_argument("image message: need a non-empty CV_8UC1 or CV_8UC3 image");
  out.width = static_cast<uint32_t>(image.cols);
  out.height = static_cast<uint32_t>(image.rows);
  out.encoding = image.channels() == 3 ? kBgr8 : kMono8;
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * image.elemSize();
  out.step = static_cast<uint32_t>(row_bytes);
  out.data.resize(row_bytes * image.rows);
  for (int y = 0; y < image.rows; ++y)
    std::copy_n(image.ptr<uint8_t>(y), row_bytes, out.data.data() + row_bytes * y);
}

}  // namespace rslam::camera
