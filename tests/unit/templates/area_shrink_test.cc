// Pins AreaShrink: each output cell is the area-weighted mean of the source pixels it covers
// (what cv::INTER_AREA computes), intensities scaled to [0, 1].
#include "services/templates/area_shrink.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "tests/unit/templates/test_images.h"

namespace rslam::templates {
namespace {

// The definition in double: cell (cx, cy) covers [cx * sx, (cx + 1) * sx) x [cy * sy, (cy + 1) * sy).
double ReferenceCell(const cv::Mat& source, int width, int height, int cx, int cy) {
  const double sx = static_cast<double>(source.cols) / width;
  const double sy = static_cast<double>(source.rows) / height;
  double sum = 0.0;
  for (int y = 0; y < source.rows; ++y) {
    const double oy = std::max(0.0, std::min<double>(y + 1, (cy + 1) * sy) - std::max<double>(y, cy * sy));
    if (oy <= 0) continue;
    for (int x = 0; x < source.cols; ++x) {
      const double ox = std::max(0.0, std::min<double>(x + 1, (cx + 1) * sx) - std::max<double>(x, cx * sx));
      sum += ox * oy * source.at<uint8_t>(y, x);
    }
  }
  return sum / (sx * sy * 255.0);
}

TEST(AreaShrinkTest, EveryCellIsTheAreaWeightedMeanOfItsPixels) {
  const cv::Mat image = testing::Texture(640, 480, 3);
  // St Lucia (560 x 150 -> 60 x 10: fractional columns, whole rows), iRat-like fractional rows,
  // a cell of one pixel, and a single output cell.
  struct Case {
    cv::Rect crop;
    int width, height;
  };
  for (const Case& c : {Case{{40, 150, 560, 150}, 60, 10}, Case{{0, 0, 640, 150}, 60, 20}, Case{{5, 7, 61, 13}, 61, 13},
                        Case{{1, 2, 97, 33}, 7, 5}, Case{{0, 0, 30, 30}, 1, 1}}) {
    const cv::Mat crop = image(c.crop);
    cv::Mat out;
    AreaShrink(crop.cols, crop.rows, c.width, c.height).Apply(crop, out);
    ASSERT_EQ(out.type(), CV_32F);
    ASSERT_EQ(out.size(), cv::Size(c.width, c.height));
    for (int y = 0; y < c.height; ++y) {
      for (int x = 0; x < c.width; ++x) {
        EXPECT_NEAR(out.at<float>(y, x), ReferenceCell(crop, c.width, c.height, x, y), 2e-6)
            << c.width << "x" << c.height << " cell " << x << "," << y;
      }
    }
    // And what OpenCV's INTER_AREA computes.
    cv::Mat opencv;
    cv::resize(crop, opencv, cv::Size(c.width, c.height), 0, 0, cv::INTER_AREA);
    cv::Mat ours8;
    out.convertTo(ours8, CV_8U, 255.0);
    EXPECT_LE(cv::norm(ours8, opencv, cv::NORM_INF), 1.0);
  }
}

TEST(AreaShrinkTest, RefusesGrowingAndWrongImages) {
  EXPECT_THROW(AreaShrink(10, 10, 11, 5), std::invalid_argument);
  EXPECT_THROW(AreaShrink(10, 10, 0, 5), std::invalid_argument);
  const AreaShrink shrink(20, 10, 4, 2);
  cv::Mat out;
  EXPECT_THROW(shrink.Apply(cv::Mat(10, 21, CV_8UC1, cv::Scalar(0)), out), std::invalid_argument);
  EXPECT_THROW(shrink.Apply(cv::Mat(10, 20, CV_8UC3, cv::Scalar(0)), out), std::invalid_argument);
}

}  // namespace
}  // namespace rslam::templates
