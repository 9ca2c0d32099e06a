#pragma once
// Where camera frames come from: an image folder or list, a video file, or a V4L2 device (all
// through OpenCV). Frames are numbered 0, 1, 2, ... and stamped: recorded sources get stamps
// from their nominal rate (deterministic, so a replay builds the same map), live devices from
// the wall clock at capture.

#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rslam::camera {

struct Frame {
  cv::Mat image;       // BGR8 or grey (CV_8UC1), as the source delivers it
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  std::string name;    // file name or "frame N"
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // The next frame, or nullopt at the end of a finite source. Throws std::runtime_error on a
  // read failure (an unreadable image file names the file; the next call goes on with the next file).
  virtual std::optional<Frame> Next() = 0;
  // Frames in a finite source, or -1 when unknown (live devices).
  virtual int64_t size() const = 0;
  virtual std::string Describe() const = 0;
};

// Image files (png, jpg, pgm, ppm, bmp, tif) in a folder, in file-name order; or, when path is
// a text file, one image path per line (relative to the list's folder). Stamps are
// start_ns + seq / fps. Throws std::invalid_argument naming the path when there are no images.
std::unique_ptr<FrameSource> OpenImageSequence(const std::string& path, double fps, int64_t start_ns = 0);

// A video file; stamps from the file's timestamps. Throws std::invalid_argument if it does not open.
std::unique_ptr<FrameSource> OpenVideoFile(const std::string& path);

// A V4L2 camera (/dev/videoN) at the requested size and rate; stamps from the wall clock.
// Throws std::invalid_argument with a clear message if the device is absent or cannot stream.
std::unique_ptr<FrameSource> OpenDevice(const std::string& device, int width, int height, double fps);

// Image files of a folder in name order (what OpenImageSequence reads).
std::vector<std::string> ListImages(const std::string& folder);

}  // namespace rslam::camera
