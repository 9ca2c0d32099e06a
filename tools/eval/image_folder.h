#pragma once
// Reads the image sets of a place-recognition evaluation from disk (part of the command, not of
// the pure evaluation library). Images are read as grey, files sorted by name.

#include <opencv2/core.hpp>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace rslam::eval {

struct ImageFolder {
  std::vector<std::string> names;  // file names, sorted
  std::vector<cv::Mat> images;     // CV_8UC1, same order
};

// Every image file (png, jpg, jpeg, bmp, pgm, ppm, tif, tiff) of dir, sorted by name, at most
// max_images of them (0 = all). Throws std::runtime_error naming the folder or file when the
// folder is missing, holds no images, or an image cannot be decoded.
ImageFolder LoadGreyImageFolder(const std::filesystem::path& dir, std::size_t max_images = 0);

// Frame-aligned reference and query sets: the same file names in both folders (same name =
// same place). Throws std::runtime_error on different counts or names.
struct FrameAlignedSets {
  ImageFolder references;
  ImageFolder queries;
};
FrameAlignedSets LoadFrameAlignedSets(const std::filesystem::path& reference_dir,
                                      const std::filesystem::path& query_dir, std::size_t max_images = 0);

}  // namespace rslam::eval
