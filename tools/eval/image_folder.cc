#include "tools/eval/image_folder.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <set>
#include <stdexcept>

namespace rslam::eval {

namespace {

bool IsImageFile(const std::filesystem::path& path) {
  static const std::set<std::string> kExtensions = {".png", ".jpg", ".jpeg", ".bmp", ".pgm", ".ppm", ".tif", ".tiff"};
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return kExtensions.count(extension) > 0;
}

}  // namespace

ImageFolder LoadGreyImageFolder(const std::filesystem::path& dir, std::size_t max_images) {
  std::error_code error;
  if (!std::filesystem::is_directory(dir, error)) {
    throw std::runtime_error("image folder '" + dir.string() + "' does not exist or is not a folder");
  }
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.is_regular_file() && IsImageFile(entry.path())) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end(),
            [](const auto& a, const auto& b) { return a.filename().string() < b.filename().string(); });
  if (files.empty()) throw std::runtime_error("image folder '" + dir.string() + "' holds no images");
  if (max_images > 0 && files.size() > max_images) files.resize(max_images);

  ImageFolder folder;
  folder.names.reserve(files.size());
  folder.images.reserve(files.size());
  for (const auto& file : files) {
    cv::Mat grey = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
    if (grey.empty()) throw std::runtime_error("cannot read image '" + file.string() + "'");
    folder.names.push_back(file.filename().string());
    folder.images.push_back(std::move(grey));
  }
  return folder;
}

FrameAlignedSets LoadFrameAlignedSets(const std::filesystem::path& reference_dir,
                                      const std::filesystem::path& query_dir, std::size_t max_images) {
  FrameAlignedSets sets{LoadGreyImageFolder(reference_dir, max_images), LoadGreyImageFolder(query_dir, max_images)};
  if (sets.references.names.size() != sets.queries.names.size()) {
    throw std::runtime_error("reference folder '" + reference_dir.string() + "' has " +
                             std::to_string(sets.references.names.size()) + " images but query folder '" +
                             query_dir.string() + "' has " + std::to_string(sets.queries.names.size()) +
                             "; frame-aligned sets need the same files in both");
  }
  for (std::size_t k = 0; k < sets.references.names.size(); ++k) {
    if (sets.references.names[k] != sets.queries.names[k]) {
      throw std::runtime_error("frame-aligned sets differ at position " + std::to_string(k) + ": reference '" +
                               sets.references.names[k] + "' vs query '" + sets.queries.names[k] + "'");
    }
  }
  return sets;
}

}  // namespace rslam::eval
