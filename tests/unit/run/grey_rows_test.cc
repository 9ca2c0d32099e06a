// ToGreyRows: the converted rows are exactly cv::cvtColor's conversion of the whole frame.
#include "tools/run/grey_rows.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <stdexcept>

namespace rslam::run {
namespace {

cv::Mat RandomImage(int rows, int cols, int type, uint64_t seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

void ExpectRowsEqual(const cv::Mat& expected, const cv::Mat& actual, int row_begin, int row_end) {
  ASSERT_EQ(actual.type(), CV_8UC1);
  ASSERT_EQ(actual.size(), expected.size());
  const cv::Range rows(row_begin, row_end);
  EXPECT_EQ(cv::countNonZero(expected.rowRange(rows) != actual.rowRange(rows)), 0)
      << "rows [" << row_begin << ", " << row_end << ")";
}

TEST(ToGreyRows, ConvertsTheRowsExactlyAsOpenCvConvertsTheWholeFrame) {
  // Widths with and without a remainder after whole 16-pixel steps.
  for (const cv::Size size : {cv::Size(640, 480), cv::Size(53, 37), cv::Size(15, 4), cv::Size(1, 1)}) {
    const cv::Mat bgr = RandomImage(size.height, size.width, CV_8UC3, 17 + size.width);
    cv::Mat expected;
    cv::cvtColor(bgr, expected, cv::COLOR_BGR2GRAY);
    cv::Mat buffer;
    ExpectRowsEqual(expected, ToGreyRows(bgr, 0, size.height, buffer), 0, size.height);
    if (size.height > 2) {
      ExpectRowsEqual(expected, ToGreyRows(bgr, 1, size.height - 1, buffer), 1, size.height - 1);
    }
  }
}

TEST(ToGreyRows, ConvertsAFrameThatIsAViewIntoALargerImage) {
  const cv::Mat big = RandomImage(500, 700, CV_8UC3, 5);
  const cv::Mat view = big(cv::Rect(31, 7, 640, 480));  // rows not contiguous in memory
  cv::Mat expected;
  cv::cvtColor(view, expected, cv::COLOR_BGR2GRAY);
  cv::Mat buffer;
  ExpectRowsEqual(expected, ToGreyRows(view, 75, 430, buffer), 75, 430);
}

TEST(ToGreyRows, ConvertsBgraRowsAsOpenCv) {
  const cv::Mat bgra = RandomImage(48, 64, CV_8UC4, 9);
  cv::Mat expected;
  cv::cvtColor(bgra, expected, cv::COLOR_BGRA2GRAY);
  cv::Mat buffer;
  ExpectRowsEqual(expected, ToGreyRows(bgra, 10, 40, buffer), 10, 40);
}

TEST(ToGreyRows, ReusesTheBufferAndReturnsGreyFramesAsTheyAre) {
  const cv::Mat bgr = RandomImage(48, 64, CV_8UC3, 3);
  cv::Mat buffer;
  ToGreyRows(bgr, 0, 48, buffer);
  const uchar* data = buffer.data;
  ToGreyRows(bgr, 5, 20, buffer);
  EXPECT_EQ(buffer.data, data) << "same size: no new allocation";
  const cv::Mat grey = RandomImage(48, 64, CV_8UC1, 4);
  EXPECT_EQ(ToGreyRows(grey, 0, 10, buffer).data, grey.data);
}

TEST(ToGreyRows, RejectsBadImagesAndRowRangesOutsideTheImage) {
  cv::Mat buffer;
  const cv::Mat bgr = RandomImage(48, 64, CV_8UC3, 1);
  EXPECT_THROW(ToGreyRows(cv::Mat(), 0, 1, buffer), std::invalid_argument);
  EXPECT_THROW(ToGreyRows(cv::Mat(48, 64, CV_16UC3, cv::Scalar::all(0)), 0, 48, buffer), std::invalid_argument);
  EXPECT_THROW(ToGreyRows(cv::Mat(48, 64, CV_8UC2, cv::Scalar::all(0)), 0, 48, buffer), std::invalid_argument);
  EXPECT_THROW(ToGreyRows(bgr, -1, 10, buffer), std::invalid_argument);
  EXPECT_THROW(ToGreyRows(bgr, 0, 49, buffer), std::invalid_argument);
  EXPECT_THROW(ToGreyRows(bgr, 10, 10, buffer), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::run
