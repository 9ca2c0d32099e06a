#include "services/camera/frame_source.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace rslam::camera {
namespace {

namespace fs = std::filesystem;

bool IsImageFile(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" || ext == ".bmp" ||
         ext == ".tif" || ext == ".tiff";
}

class ImageSequence final : public FrameSource {
 public:
  ImageSequence(std::vector<std::string> files, double fps, int64_t start_ns, std::string origin)
      : files_(std::move(files)), period_ns_(1e9 / fps), start_ns_(start_ns), origin_(std::move(origin)) {}

  std::optional<Frame> Next() override {
    if (next_ >= files_.size()) return std::nullopt;
    // The index advances even when the file cannot be read: the caller may skip a bad file and
    // go on, and frame numbers (and stamps) stay tied to file positions.
    const std::size_t index = next_++;
    const std::string& file = files_[index];
    Frame f;
    f.seq = index;
    f.stamp_ns = start_ns_ + static_cast<int64_t>(static_cast<double>(index) * period_ns_);
    f.name = fs::path(file).filename().string();
    f.image = cv::imread(file, cv::IMREAD_UNCHANGED);
    if (f.image.empty()) throw std::runtime_error(file + ": cannot read image");
    if (f.image.depth() != CV_8U) throw std::runtime_error(file + ": not an 8-bit image");
    if (f.image.channels() == 4) f.image = cv::imread(file, cv::IMREAD_COLOR);  // drop alpha
    return f;
  }
  int64_t size() const override { return static_cast<int64_t>(files_.size()); }
  std::string Describe() const override { return origin_ + " (" + std::to_string(files_.size()) + " images)"; }

 private:
  const std::vector<std::string> files_;
  const double period_ns_;
  const int64_t start_ns_;
  const std::string origin_;
  std::size_t next_ = 0;
};

class VideoCaptureSource final : public FrameSource {
 public:
  VideoCaptureSource(cv::VideoCapture capture, std::string origin, bool live)
      : capture_(std::move(capture)), origin_(std::move(origin)), live_(live) {}

  std::optional<Frame> Next() override {
    Frame f;
    if (!capture_.read(f.image) || f.image.empty()) {
      if (live_) throw std::runtime_error(origin_ + ": the device stopped delivering frames");
      return std::nullopt;
    }
    f.seq = next_++;
    f.name = "frame " + std::to_string(f.seq);
    if (live_) {
      f.stamp_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                       std::chrono::system_clock::now().time_since_epoch()).count();
    } else {
      f.stamp_ns = static_cast<int64_t>(capture_.get(cv::CAP_PROP_POS_MSEC) * 1e6);
    }
    return f;
  }
  int64_t size() const override {
    if (live_) return -1;
    const double n = const_cast<cv::VideoCapture&>(capture_).get(cv::CAP_PROP_FRAME_COUNT);
    return n > 0 ? static_cast<int64_t>(n) : -1;
  }
  std::string Describe() const override { return origin_; }

 private:
  cv::VideoCapture capture_;
  const std::string origin_;
  const bool live_;
  uint64_t next_ = 0;
};

}  // namespace

std::vector<std::string> ListImages(const std::string& folder) {
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.is_regular_file() && IsImageFile(entry.path())) files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

std::unique_ptr<FrameSource> OpenImageSequence(const std::string& path, double fps, int64_t start_ns) {
  if (!(fps > 0)) throw std::invalid_argument("frame rate must be positive");
  if (!fs::exists(path)) throw std::invalid_argument(path + ": no such folder or list file");
  std::vector<std::string> files;
  if (fs::is_directory(path)) {
    files = ListImages(path);
  } else {
    std::ifstream list(path);
    const fs::path base = fs::path(path).parent_path();
    std::string line;
    while (std::getline(list, line)) {
      if (line.empty() || line[0] == '#') continue;
      const fs::path p(line);
      files.push_back((p.is_absolute() ? p : base / p).string());
    }
  }
  if (files.empty()) throw std::invalid_argument(path + ": no images found");
  return std::make_unique<ImageSequence>(std::move(files), fps, start_ns, path);
}

std::unique_ptr<FrameSource> OpenVideoFile(const std::string& path) {
  if (!fs::is_regular_file(path)) throw std::invalid_argument(path + ": no such video file");
  cv::VideoCapture capture(path);
  if (!capture.isOpened()) throw std::invalid_argument(path + ": cannot open as a video");
  return std::make_unique<VideoCaptureSource>(std::move(capture), path, false);
}

std::unique_ptr<FrameSource> OpenDevice(const std::string& device, int width, int height, double fps) {
  if (!fs::exists(device))
    throw std::invalid_argument(device + ": no such camera device (is the camera connected? see `ls /dev/video*`)");
  cv::VideoCapture capture(device, cv::CAP_V4L2);
  if (!capture.isOpened()) throw std::invalid_argument(device + ": cannot open as a V4L2 camera");
  if (width > 0) capture.set(cv::CAP_PROP_FRAME_WIDTH, width);
  if (height > 0) capture.set(cv::CAP_PROP_FRAME_HEIGHT, height);
  if (fps > 0) capture.set(cv::CAP_PROP_FPS, fps);
  return std::make_unique<VideoCaptureSource>(std::move(capture), device, true);
}

}  // namespace rslam::camera
