#include "tools/eval/image_folder.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <functional>
#include <stdexcept>

#include "tests/support/child_process.h"
#include "tests/unit/eval/eval_test_files.h"

namespace rslam::eval {
namespace {

using rslam::testing::ScratchFolderForTest;
using testing::WriteText;

void WriteImages(const std::filesystem::path& dir, int count, int value) {
  for (int k = 0; k < count; ++k) {
    cv::imwrite((dir / ("images-" + std::to_string(10 + k) + ".png")).string(),
                cv::Mat(32, 64, CV_8UC3, cv::Scalar::all(value + k)));
  }
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ImageFolder, LoadsGreyImagesSortedByName) {
  const auto dir = ScratchFolderForTest();
  WriteImages(dir, 3, 50);
  WriteText(dir / "notes.txt", "not an image");
  const ImageFolder folder = LoadGreyImageFolder(dir);
  ASSERT_EQ(folder.names.size(), 3u);
  EXPECT_EQ(folder.names[0], "images-10.png");
  EXPECT_EQ(folder.images[2].channels(), 1);
  EXPECT_EQ(folder.images[2].at<uint8_t>(0, 0), 52);
  EXPECT_EQ(LoadGreyImageFolder(dir, 2).images.size(), 2u);
  std::filesystem::remove_all(dir);
}

TEST(ImageFolder, BadFoldersGiveClearErrors) {
  const auto dir = ScratchFolderForTest();
  EXPECT_NE(ErrorOf([&] { LoadGreyImageFolder(dir); }).find("holds no images"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { LoadGreyImageFolder(dir / "missing"); }).find("does not exist"), std::string::npos);
  WriteText(dir / "broken.png", "this is not a png");
  EXPECT_NE(ErrorOf([&] { LoadGreyImageFolder(dir); }).find("cannot read image"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(ImageFolder, FrameAlignedSetsMustHoldTheSameFiles) {
  const auto dir = ScratchFolderForTest();
  std::filesystem::create_directories(dir / "summer");
  std::filesystem::create_directories(dir / "winter");
  WriteImages(dir / "summer", 3, 10);
  WriteImages(dir / "winter", 2, 10);
  EXPECT_NE(ErrorOf([&] { LoadFrameAlignedSets(dir / "summer", dir / "winter"); }).find("has 3 images"),
            std::string::npos);
  std::filesystem::rename(dir / "winter/images-10.png", dir / "winter/other.png");
  WriteImages(dir / "winter", 1, 10);  // images-10 again
  std::filesystem::rename(dir / "winter/other.png", dir / "winter/images-99.png");
  EXPECT_NE(ErrorOf([&] { LoadFrameAlignedSets(dir / "summer", dir / "winter"); }).find("differ at position 2"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rslam::eval
